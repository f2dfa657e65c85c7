"""Single-object densities held as arrays, predicted and updated all at once."""
