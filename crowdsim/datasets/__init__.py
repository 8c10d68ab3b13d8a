"""Labelled datasets: generation (``generate``), the layout (``layout``, docs/dataset-format.md), reading
(``reader``: ``Dataset``, ``Episode``, ``FrameSamples``) and detector scoring (``detection_eval``).

The names below are imported on first use, so that ``import crowdsim.datasets`` costs nothing and needs neither
h5py nor pyarrow (the ``data`` extra) until a dataset is read.
"""

from importlib import import_module

_WHERE = {"Dataset": "reader", "Episode": "reader", "FrameSamples": "reader", "collate": "reader",
          "DatasetError": "layout", "evaluate_detector": "detection_eval"}
__all__ = list(_WHERE)


def __getattr__(name: str):
    if name in _WHERE:
        return getattr(import_module(f".{_WHERE[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
