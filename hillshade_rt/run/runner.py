"""The skeleton every run shares: what each command does before its own work and after it, once.

Before (:meth:`RunContext.start`): the paths the run writes claimed against its inputs and each
other (``io.write.Claims``: no output may be an input, none twice), the numba threads set
(``--threads``, :func:`.config.set_threads`), the backend chosen by the one rule
(``engine.gpu.resolve_backend``), the note that kernels are about to compile, the stage timer.
After (:meth:`RunContext.finish`): the report written (``--report``) and the lines for people
said in order (notes, the summary), nothing when ``--quiet``.

A command's run is then its own named steps between the two::

    ctx = RunContext.start(cfg.run, inputs=[cfg.dem], outputs=[(cfg.output, "OUTPUT")],
                           algorithm=cfg.algorithm)
    ...                               # read, prepare, compute, write (``ctx.timer``)
    return ctx.finish(report, [("summary", line)])
"""

from __future__ import annotations

from dataclasses import dataclass, field

from .config import RunOptions, set_threads
from .report import Timer

PHASES = ("read", "prepare", "compute", "write")     # the reports' seconds, in order


@dataclass(eq=False)
class RunContext:
    """A run under way: its options, claims, timer, threads and backend.

    Attributes
    ----------
    ro : RunOptions
        How the run goes (backend asked for, threads, report, overwrite, messages).
    claims : io.write.Claims
        The paths claimed so far (``claim`` more as the run learns them).
    timer : Timer
        Seconds per stage (``with ctx.timer("compute"): ...``).
    backend : str or None
        ``cpu`` or ``gpu``: the backend chosen (None for a run without kernels of a backend).
    threads : int
        numba's threads in use.
    """

    ro: RunOptions
    claims: object
    timer: Timer = field(default_factory=Timer)
    backend: str | None = None
    threads: int = 1

    @classmethod
    def start(cls, ro: RunOptions, *, inputs=(), outputs=(), algorithm: str | None = None,
              options=None, backend: bool = True, relief: bool = False,
              note: bool = True) -> RunContext:
        """Begin a run: claim ``outputs`` ((path, what) pairs; None paths skipped; or a
        callable taking the claims, for an output with checks of its own, run in its turn) and
        the report and preview against ``inputs``; set the threads; choose the backend (``backend``
        False: a run with no GPU kernels, always the CPU) for ``algorithm`` and ``options``;
        say the compile note of ``algorithm`` (``relief``: the relief kernels too) unless
        ``note`` is False or the run is quiet."""
        from ..io.write import Claims
        claims = Claims(list(inputs), ro.overwrite)
        ctx = cls(ro, claims)
        for entry in list(outputs) + [(ro.report_path, "--report"),
                                      (ro.preview, "--preview")]:
            if callable(entry):
                entry(claims)
            elif entry[0] is not None:
                claims.claim(*entry)
        ctx.threads = set_threads(ro)
        if backend:
            from ..engine.gpu import resolve_backend
            ctx.backend = resolve_backend(ro.backend, algorithm, dict(options or {}))
        else:
            ctx.backend = "cpu"
        if note and algorithm is not None:
            ctx.compile_note(algorithm, relief)
        return ctx

    def claim(self, path, what: str) -> str:
        """Claim one more path the run writes (``io.write.Claims.claim``)."""
        return self.claims.claim(path, what)

    def compile_note(self, algorithm: str, relief: bool = False) -> None:
        """Say that numba is about to compile ``algorithm``'s kernels, when they are not cached
        (``run.notes.compile_note``)."""
        if self.ro.quiet:
            return
        from .notes import compile_note
        line = compile_note(algorithm, self.backend or "cpu", relief)
        if line:
            self.ro.say("compile", line)

    def say(self, kind: str, message: str | None) -> None:
        """A line for people (kind "note", "summary", "compile"), unless quiet or None."""
        if message and not self.ro.quiet:
            self.ro.say(kind, message)

    def seconds(self) -> dict:
        """The stages' seconds and the total so far (the reports' ``seconds``)."""
        return dict(self.timer.seconds, total=self.timer.total())

    def phase_seconds(self) -> dict:
        """:meth:`seconds` with every phase (read, prepare, compute, write; 0.0 when the run
        had none) and the total, as the reports of the lighting commands give them."""
        return {**{k: 0.0 for k in PHASES}, **self.seconds()}

    def finish(self, report: dict, lines=()) -> dict:
        """End the run: write ``report`` (``--report``, JSON, atomically), then say ``lines``
        ((kind, message) pairs, in order; None messages skipped) unless quiet. Returns the
        report."""
        if self.ro.report_path is not None:
            from ..io import write_json
            write_json(self.ro.report_path, report, self.ro.overwrite)
        for kind, message in lines:
            self.say(kind, message)
        return report
