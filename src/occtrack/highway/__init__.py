"""The simulated four-lane highway of the paper's appendix (Table III): traffic, a sensor that
sees by angle, particle multi-Bernoulli trackers with three occlusion handlers, and scoring."""
