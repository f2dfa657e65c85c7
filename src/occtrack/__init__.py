"""occtrack: occlusion-aware multi-object tracking.

Implements "Measurement-wise Occlusion in Multi-object Tracking" (Motro and Ghosh): a Poisson
multi-Bernoulli tracker in which occlusion is one swappable step (none, object-wise,
measurement-wise), and the paper's four uses of it.
"""

__version__ = "0.1.0"
