"""errors.py: the exceptions' family (what the command line catches as one line) and the
signal an interruption carries."""

import signal

import pytest

from hillshade_rt import errors


def test_usage_problem_and_all_nodata_are_hillshade_errors():
    assert issubclass(errors.UsageProblem, errors.HillshadeError)
    assert issubclass(errors.AllNodata, errors.HillshadeError)
    assert issubclass(errors.HillshadeError, Exception)
    assert issubclass(errors.HillshadeWarning, UserWarning)
    with pytest.raises(errors.HillshadeError, match="^one line$"):
        raise errors.UsageProblem("one line")


def test_interrupted_is_a_keyboard_interrupt_with_its_signal():
    e = errors.Interrupted(signal.SIGTERM)
    assert isinstance(e, KeyboardInterrupt) and not isinstance(e, Exception)
    assert e.signum == signal.SIGTERM and e.args == (signal.SIGTERM,)
