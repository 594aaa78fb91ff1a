"""Exceptions raised for bad input; the CLI turns them into one-line errors."""


class HillshadeError(Exception):
    """A problem with the user's input or environment (not a bug in hillshade-rt).

    The message is one line that names the problem; the CLI prints it and exits non-zero.
    """
