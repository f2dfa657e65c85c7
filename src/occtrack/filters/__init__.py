"""Multi-object filters: the Gaussian-mixture Poisson multi-Bernoulli filter."""
