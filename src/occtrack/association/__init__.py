"""Data association: marginal probabilities that object i produced measurement j."""

from occtrack.association.exact import exact_marginals
from occtrack.association.lbp import lbp_marginals, lbp_sparse

__all__ = ["exact_marginals", "lbp_marginals", "lbp_sparse"]
