"""Models of one object: motion, measurement, Markov features, births."""
