"""The one base of every error a user can cause (a file, a key, an argument that cannot be used): the command line
prints it as one line, and ``crowdsim.Error`` catches them all. It lives here, below every package, so that the
scenario loader, the evaluation and the commands can all derive from it."""


class Error(ValueError):
    """A fault in what the user gave: its message names the file, the key or the argument, and what was expected."""
