"""Built-in scenes: the four-square example, synthetic pedestrians, MOT sequences, the highway."""
