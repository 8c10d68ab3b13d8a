"""Detectors: each turns one sensor's frame into ``DetectedPersons`` in that sensor's frame."""
