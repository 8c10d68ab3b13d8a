"""Trackers and their parts: each tracker has ``update(stamp, detections) -> TrackedPersons`` and ``reset()``."""
