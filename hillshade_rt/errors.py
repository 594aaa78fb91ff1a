"""Exceptions raised for bad input; the CLI turns them into one-line errors."""


class HillshadeError(Exception):
    """A problem with the user's input or environment (not a bug in hillshade-rt).

    The message is one line that names the problem; the CLI prints it and exits non-zero.
    """


class UsageProblem(HillshadeError):
    """Bad input that is the command line's own fault (two options naming one file, say): the
    CLI exits with status 2 as for any malformed command line."""


class AllNodata(HillshadeError):
    """Every cell of the DEM (or of the tile of a ``--context`` run) is nodata: nothing to
    shade. The lighting and horizon runs catch it and write their outputs all nodata, with a
    note (a tile of the sea must not stop a Makefile); what cannot write such an output (the
    viewer, points) lets it stand as the error."""


class Interrupted(KeyboardInterrupt):
    """SIGINT, SIGTERM or SIGHUP received: the run stops, removes what is unfinished and the
    command line exits with 128 + the signal's number."""

    def __init__(self, signum: int):
        super().__init__(signum)
        self.signum = signum


class HillshadeWarning(UserWarning):
    """Something a run's user should know that does not stop it (an extrapolated ΔT, say): its
    message is one line, which the command line prints as ``hillshade-rt: warning: ...``."""
