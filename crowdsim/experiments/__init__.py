"""Experiments that take long: many runs or a training, one table or curve."""
