"""Shadow algorithms, and the one registry of what the rest of the package knows about them.

Each algorithm module exposes ``shadow_mask(z, rays, zmax=None, stats=None, **options) -> uint8
mask``: ``z`` 2-D float32 heights (NaN voids, never copied), ``rays`` a ``geometry.SunRays``,
``zmax`` the highest valid height, ``stats`` an optional dict the algorithm fills with figures for
the report. Where it has a CUDA kernel, also ``shadow_mask_gpu(g, rays, zmax, stats=None,
**options)``, the same on the GPU, where ``g`` is a ``gpu.GpuDem`` holding the heights on the
device; kernels are written with ``_cuda`` (one source for both targets).

**The registry.** :data:`REGISTRY` holds one :class:`AlgorithmSpec` per algorithm, in the order
the command line offers them: its one-line summary, whether it is exact, its CPU and GPU
functions, its options (:class:`OptionSpec`: keyword, flag, kind, choices, default, help), whether
``auto`` may pick it, what it costs the planner per cell. The command line generates
``--algorithm`` and the algorithm flags from it (:func:`algorithm_help`, :data:`OPTIONS`,
:func:`options_from_cli`, :func:`algorithm_for`, :func:`options_for`); the planner, the GPU
checks (:func:`gpu_unsupported`) and the shading engine read it too. Adding an algorithm = one
module + one entry here.

**Cheap to import.** This module imports neither numpy nor numba, and no algorithm module: the
command line reads the registry to build its options before any of that is loaded, and an
algorithm's module is imported at its first call (:class:`FunctionRef`). Kernel modules take
``njit`` from ``_jitcache``, so their numba cache is right however they are imported.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass

from ..errors import HillshadeError, UsageProblem


@dataclass(frozen=True)
class FunctionRef:
    """A function of an algorithm module, imported at its first use: ``ref(*args, **kw)`` calls
    it, ``ref.load()`` returns it (no numba is loaded before either)."""

    module: str       # the module under hillshade_rt.algorithms, e.g. "brute"
    name: str         # the function, e.g. "shadow_mask"

    def load(self):
        return getattr(importlib.import_module(f"{__name__}.{self.module}"), self.name)

    def __call__(self, *args, **kwargs):
        return self.load()(*args, **kwargs)


@dataclass(frozen=True)
class OptionSpec:
    """One option of one algorithm: the keyword its ``shadow_mask`` (and ``shadow_mask_gpu``)
    takes, and the command-line flag that sets it.

    ``kind`` is ``"choice"`` (one of ``choices``), ``"int"`` (at least ``min``) or ``"flag"``
    (given or not: the keyword then takes ``flag_value``). ``default`` is the algorithm's own
    value when the option is not given (the command line's default is None: "not given").
    ``approximate``: some of its values make the mask approximate. ``cpu_only``: the values
    that have no GPU kernel, and ``cpu_only_why`` why (said to the user)."""

    keyword: str
    flag: str
    kind: str
    help: str
    default: object
    choices: tuple[str, ...] = ()
    min: int | None = None
    flag_value: object = True
    approximate: bool = False
    cpu_only: tuple = ()
    cpu_only_why: str = ""

    def __post_init__(self):
        if self.kind not in ("choice", "int", "flag"):
            raise ValueError(f"{self.flag}: kind must be choice, int or flag, not {self.kind!r}")

    @property
    def param(self) -> str:
        """The command line's parameter name (click's, from the flag): ``--horizon-method`` ->
        ``horizon_method``."""
        return self.flag.lstrip("-").replace("-", "_")

    def from_cli(self, value):
        """The keyword's value for the command line's ``value`` of this option; None when it was
        not given (a flag: False or None)."""
        if self.kind == "flag":
            return self.flag_value if value else None
        return value

    def gpu_refusal(self, value) -> str | None:
        """Why the keyword's ``value`` cannot run on the GPU (None when it can)."""
        key = bool(value) if self.kind == "flag" else value
        if key not in self.cpu_only:
            return None
        shown = self.flag if self.kind == "flag" else f"{self.flag} {value}"
        return f"{shown} has no GPU kernel ({self.cpu_only_why})"


@dataclass(frozen=True)
class AlgorithmSpec:
    """Everything the package knows about one algorithm outside its own module.

    ``summary``: one line for ``--help``. ``exact``: equals ``brute`` cell for cell (with its
    options at their defaults). ``cpu``/``gpu``: its ``shadow_mask`` and ``shadow_mask_gpu``
    (``gpu`` None: no GPU kernel, and ``no_gpu`` says so to the user). ``options``: its own
    options, each owned by this algorithm only. ``auto_candidate``: ``auto`` may pick it
    (``auto.choose``). ``bytes_per_cell``: working memory per window cell while it lights one
    (an upper bound measured by benchmarks/bigdem.py; the planner adds the product's).
    ``kernel_modules``: the modules whose CPU kernels a run compiles (``_jitcache.cached``: the
    first run's note). ``field_march``: it can march each cell with its own sun when the sun
    varies across the raster (``engine.shader.field_method``). ``lift``: its ``shadow_mask`` (and
    ``shadow_mask_gpu``, and the per-cell sun's march) take ``lift``, the metres above each cell
    its ray starts from (``--height-above-ground``; :func:`for_lift`)."""

    name: str
    summary: str
    exact: bool
    cpu: FunctionRef
    gpu: FunctionRef | None = None
    options: tuple[OptionSpec, ...] = ()
    auto_candidate: bool = False
    no_gpu: str = ""
    bytes_per_cell: int = 20
    kernel_modules: tuple[str, ...] = ()
    field_march: bool = False
    lift: bool = False

    @property
    def implied_by_options(self) -> bool:
        """Whether ``--algorithm auto`` given options of this algorithm only runs it: an exact
        algorithm none of whose options makes it approximate (smap's ``--nextv``, brute's
        ``--no-pyramid``). auto has no options of its own, and while SMap was the default
        ``--nextv quad`` alone ran it; options of the approximate methods (sweep, the horizon's
        hull or sample spacing) still need their algorithm named: an approximate mask is never
        chosen for the user."""
        return self.exact and bool(self.options) and not any(o.approximate for o in self.options)

    def gpu_refusal(self, options: dict) -> str | None:
        """Why this algorithm with these options cannot run on the GPU (None when it can)."""
        if self.gpu is None:
            return self.no_gpu or f"--algorithm {self.name} has no GPU kernel"
        for opt in self.options:
            why = opt.gpu_refusal(options.get(opt.keyword))
            if why:
                return why
        return None


REGISTRY: dict[str, AlgorithmSpec] = {spec.name: spec for spec in (
    AlgorithmSpec(
        "auto", exact=True,
        summary="the fastest exact method for this DEM, sun and backend (bounds or brute; the "
                "report says which ran and why)",
        cpu=FunctionRef("auto", "shadow_mask"), gpu=FunctionRef("auto", "shadow_mask_gpu"),
        bytes_per_cell=13, kernel_modules=("bounds", "brute", "pyramid"), field_march=True),
    AlgorithmSpec(
        "bounds", exact=True, auto_candidate=True,
        summary="exact, guaranteed horizon bounds + pyramid march",
        cpu=FunctionRef("bounds", "shadow_mask"), gpu=None,
        no_gpu="--algorithm bounds has no GPU kernel (its sweep runs line after line); "
               "--algorithm auto or brute use the pyramid march on the GPU",
        bytes_per_cell=13, kernel_modules=("bounds", "brute", "pyramid"), field_march=True),
    AlgorithmSpec(
        "brute", exact=True, auto_candidate=True,
        summary="exact reference march (over a max-height pyramid unless --no-pyramid)",
        cpu=FunctionRef("brute", "shadow_mask"), gpu=FunctionRef("brute", "shadow_mask_gpu"),
        options=(
            OptionSpec("pyramid", "--no-pyramid", "flag", default=True, flag_value=False,
                       help="brute: the plain march, every sample taken (same mask; the "
                            "benchmarks' reference)."),),
        bytes_per_cell=13, kernel_modules=("brute", "pyramid"), field_march=True, lift=True),
    AlgorithmSpec(
        "smap", exact=True,
        summary="exact (a seed's method: Sakalauskas' shadow map)",
        cpu=FunctionRef("smap", "shadow_mask"), gpu=FunctionRef("smap", "shadow_mask_gpu"),
        options=(
            OptionSpec("nextv", "--nextv", "choice", default="scan",
                       choices=("scan", "binary", "quad"),
                       help="smap: how NextV is built (same result; default scan)."),
            OptionSpec("better_nextv", "--better-nextv", "flag", default=False,
                       help="smap: skip silhouettes hidden by nearer ones (paper's section 9).",
                       cpu_only=(True,),
                       cpu_only_why="its per-beam stacks are as long as a beam")),
        bytes_per_cell=15, kernel_modules=("smap",)),
    AlgorithmSpec(
        "horizon", exact=True,
        summary="exact (a seed's method: each cell's horizon angle by a scan; "
                "--horizon-method hull approximates)",
        cpu=FunctionRef("horizon", "shadow_mask"),
        gpu=FunctionRef("horizon", "shadow_mask_gpu"),
        options=(
            OptionSpec("method", "--horizon-method", "choice", default="scan",
                       choices=("scan", "hull"), approximate=True,
                       help="horizon: exact per-cell scan (default) or the faster convex-hull "
                            "approximation.",
                       cpu_only=("hull",),
                       cpu_only_why="its per-line hulls are as long as a line"),
            OptionSpec("sample_spacing", "--sample-spacing", "int", default=1, min=1,
                       approximate=True,
                       help="horizon scan: use every N-th sample only (faster, approximate; "
                            "default 1).")),
        bytes_per_cell=19, kernel_modules=("horizon",)),
    AlgorithmSpec(
        "sweep", exact=False,
        summary="approximate (see docs/algorithms.md)",
        cpu=FunctionRef("sweep", "shadow_mask"), gpu=FunctionRef("sweep", "shadow_mask_gpu"),
        options=(
            OptionSpec("exact_steps", "--exact-steps", "int", default=8, min=1,
                       help="sweep: samples marched exactly before stored values are reused "
                            "(default 8)."),),
        bytes_per_cell=12, kernel_modules=("sweep",)),
)}

# keyword -> (the algorithm that owns it, the option): every algorithm option, in --help order
OPTIONS: dict[str, tuple[AlgorithmSpec, OptionSpec]] = {
    opt.keyword: (spec, opt) for spec in REGISTRY.values() for opt in spec.options}

# the functions alone, for callers that need nothing else (FunctionRefs: imported when called)
ALGORITHMS = {name: spec.cpu for name, spec in REGISTRY.items()}
GPU_ALGORITHMS = {name: spec.gpu for name, spec in REGISTRY.items() if spec.gpu is not None}


def lookup(algorithm: str) -> AlgorithmSpec:
    """The registry's entry for ``algorithm``; an unknown name is a HillshadeError listing
    the known ones."""
    try:
        return REGISTRY[algorithm]
    except KeyError:
        raise HillshadeError(f"unknown algorithm {algorithm!r}; choose one of "
                             f"{', '.join(REGISTRY)}") from None


def gpu_unsupported(algorithm: str, options: dict) -> str | None:
    """Why these options cannot run on the GPU backend (None when they can)."""
    spec = REGISTRY.get(algorithm)
    return None if spec is None else spec.gpu_refusal(options)


def algorithm_help() -> str:
    """``--algorithm``'s help: each algorithm's summary, in the registry's order."""
    return "; ".join(f"{spec.name}: {spec.summary}" for spec in REGISTRY.values()) + "."


def options_from_cli(params: dict) -> dict:
    """Take the algorithm options out of the command line's parameters (``params``, keyed by
    ``OptionSpec.param``; removed from it): ``{keyword: value}`` with None for those not given
    (``--no-pyramid`` given: ``{"pyramid": False, ...}``)."""
    return {kw: opt.from_cli(params.pop(opt.param, None)) for kw, (_, opt) in OPTIONS.items()}


def algorithm_for(algorithm: str, given: dict) -> str:
    """``algorithm``, or for ``auto`` given options of one algorithm that they imply
    (``AlgorithmSpec.implied_by_options``: smap's ``--nextv``, brute's ``--no-pyramid``), that
    algorithm. ``given``: ``{keyword: value}``, None for not given."""
    owners = {OPTIONS[k][0].name for k, v in given.items() if v is not None and k in OPTIONS}
    if algorithm == "auto" and len(owners) == 1:
        owner = REGISTRY[next(iter(owners))]
        if owner.implied_by_options:
            return owner.name
    return algorithm


def options_for(algorithm: str, given: dict) -> dict:
    """The options given (not None) for ``algorithm``, as its keywords; an unknown keyword, or
    an option of another algorithm, is a UsageProblem (``--sample-spacing 4 --algorithm brute``
    would otherwise be silently ignored)."""
    unknown = set(given) - set(OPTIONS)
    if unknown:
        raise UsageProblem(f"unknown algorithm option(s) {', '.join(sorted(unknown))} (known: "
                           f"{', '.join(sorted(OPTIONS))})")
    out = {}
    for keyword, value in given.items():
        if value is None:
            continue
        owner, opt = OPTIONS[keyword]
        if owner.name != algorithm:
            raise UsageProblem(f"{opt.flag} applies to --algorithm {owner.name}, not {algorithm}")
        out[keyword] = value
    return out


def for_lift(algorithm: str) -> str:
    """The algorithm that lights ``algorithm``'s cells from an observer above the ground
    (``--height-above-ground`` > 0): one that takes a lift itself (``AlgorithmSpec.lift``:
    brute, the exact reference march), ``auto``'s pick brute (the bounds take no lift);
    any other named algorithm is a UsageProblem naming those that can (an explicit choice is
    not swapped behind the user's back)."""
    spec = lookup(algorithm)
    can = [name for name, s in REGISTRY.items() if s.lift]
    if spec.lift:
        return algorithm
    if algorithm == "auto":
        return can[0]
    raise UsageProblem(f"--height-above-ground: --algorithm {algorithm} cannot start the rays "
                       f"above the ground; use --algorithm {' or '.join(can + ['auto'])} "
                       f"(auto runs {can[0]} then)")
