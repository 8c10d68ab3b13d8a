"""crowdsim: a synthetic-crowd testbed for people perception and social robot navigation."""

__version__ = "0.1.0"

from . import envs  # noqa: E402,F401  (registers the gymnasium environments)
