"""The algorithm registry (``hillshade_rt.algorithms``, issue 19): one entry per algorithm holds
every fact the rest of the package needs, and says what the code it describes does.

The command line generates ``--algorithm`` and the algorithm flags from it (``cli/options.py``):
these tests check the generated options fact for fact, and that ``algorithm_for`` /
``options_for`` decide as the command line always has."""

import inspect
import itertools
import os
import subprocess
import sys

import click
import click.testing
import pytest

from hillshade_rt import algorithms as alg
from hillshade_rt import cli as cli_mod
from hillshade_rt.algorithms import (OPTIONS, REGISTRY, algorithm_for, gpu_unsupported,
                                     options_for, options_from_cli)
from hillshade_rt.errors import HillshadeError, UsageProblem


def test_importing_the_registry_loads_no_numpy_numba_or_algorithm():
    code = ("import sys, hillshade_rt.algorithms as a; a.algorithm_help(); list(a.OPTIONS); "
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'numba') "
            "or m.startswith('hillshade_rt.algorithms.')))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       env=dict(os.environ))
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "[]"


def test_entries_name_their_functions_and_options_their_keywords():
    """Each entry's functions exist; each option is a keyword of its algorithm's shadow_mask
    (and shadow_mask_gpu, but for brute's pyramid on the GPU: the CPU's only) with the
    registry's default."""
    for name, spec in REGISTRY.items():
        assert spec.name == name and spec.summary and "\n" not in spec.summary
        cpu = inspect.signature(spec.cpu.load()).parameters
        gpu = inspect.signature(spec.gpu.load()).parameters if spec.gpu else {}
        for opt in spec.options:
            assert cpu[opt.keyword].default == opt.default, (name, opt.keyword)
            if spec.gpu and opt.keyword in gpu:
                assert gpu[opt.keyword].default == opt.default, (name, opt.keyword)
            if opt.kind == "choice":
                assert opt.default in opt.choices
    assert set(alg.ALGORITHMS) == set(REGISTRY)
    assert set(alg.GPU_ALGORITHMS) == {n for n, s in REGISTRY.items() if s.gpu is not None}


def test_keywords_and_flags_are_unique():
    opts = [opt for spec in REGISTRY.values() for opt in spec.options]
    assert len({o.keyword for o in opts}) == len(opts) == len(OPTIONS)
    assert len({o.flag for o in opts}) == len(opts)


def test_auto_picks_only_its_candidates():
    from hillshade_rt.algorithms import auto
    from hillshade_rt.model.geometry import Grid, sun_rays
    candidates = {n for n, s in REGISTRY.items() if s.auto_candidate}
    assert candidates == {"bounds", "brute"}
    grid = Grid.uniform(300, 300, 30.0)
    seen = set()
    for el, relief in [(3.0, 2000.0), (60.0, 1.0), (10.0, 500.0)]:
        rays = sun_rays(grid, 203.7, el)
        for backend in ("cpu", "gpu"):
            seen.add(auto.choose((300, 300), 1.0, (0.0, relief), rays, backend)[0])
    assert seen <= candidates and len(seen) == 2
    assert all(REGISTRY[n].exact for n in candidates)


# ---------------------------------------------------------------------------------------------
# the command line's hand-written facts, from the registry

def _shadow_params():
    return {p.name: p for p in cli_mod.cli.commands["shadow"].params}


def test_cli_algorithm_option_is_the_registrys():
    opt = _shadow_params()["algorithm"]
    assert list(opt.type.choices) == list(REGISTRY) and opt.default == "auto"
    for spec in REGISTRY.values():       # the help has every algorithm's summary
        assert f"{spec.name}: {spec.summary}" in opt.help


def test_cli_algorithm_flags_are_the_registrys():
    params = _shadow_params()
    for keyword, (spec, opt) in OPTIONS.items():
        p = params[opt.param]
        assert p.opts == [opt.flag] and p.default is None and p.help == opt.help, opt.flag
        if opt.kind == "flag":
            assert p.is_flag
        elif opt.kind == "choice":
            assert isinstance(p.type, click.Choice) and tuple(p.type.choices) == opt.choices
        else:
            assert isinstance(p.type, click.IntRange) and p.type.min == opt.min
        assert opt.help.startswith(spec.name)          # "smap: ...", "horizon scan: ..."


def _given_combinations():
    values = {"nextv": "quad", "better_nextv": True, "method": "hull", "sample_spacing": 4,
              "exact_steps": 2, "pyramid": False}
    assert set(values) == set(OPTIONS)
    keys = sorted(values)
    for n in range(3):
        for combo in itertools.combinations(keys, n):
            yield {k: (values[k] if k in combo else None) for k in keys}


# the command line's rule before the registry (cli.py's _algorithm_for / _algorithm_options),
# restated: auto given options of exactly one of smap or brute runs that algorithm; an option of
# another algorithm than the one that runs is a usage error naming its flag
_OWNER = {"nextv": "smap", "better_nextv": "smap", "method": "horizon",
          "sample_spacing": "horizon", "exact_steps": "sweep", "pyramid": "brute"}
_FLAG = {"nextv": "--nextv", "better_nextv": "--better-nextv", "method": "--horizon-method",
         "sample_spacing": "--sample-spacing", "exact_steps": "--exact-steps",
         "pyramid": "--no-pyramid"}


def _old_rule(algorithm, given):
    owners = {_OWNER[k] for k, v in given.items() if v is not None}
    if algorithm == "auto" and len(owners) == 1 and owners <= {"smap", "brute"}:
        algorithm = owners.pop()
    for k, v in given.items():
        if v is not None and _OWNER[k] != algorithm:
            return algorithm, f"{_FLAG[k]} applies to --algorithm {_OWNER[k]}, not {algorithm}"
    return algorithm, {k: v for k, v in given.items() if v is not None}


def test_algorithm_for_and_options_for_decide_as_the_cli_always_has():
    for given in _given_combinations():
        for algorithm in REGISTRY:
            chosen = algorithm_for(algorithm, given)
            want_algorithm, want = _old_rule(algorithm, given)
            assert chosen == want_algorithm, (algorithm, given)
            if isinstance(want, str):
                with pytest.raises(UsageProblem) as got:
                    options_for(chosen, given)
                assert str(got.value) == want
            else:
                assert options_for(chosen, given) == want


def test_options_for_refuses_unknown_keywords():
    with pytest.raises(UsageProblem, match=r"unknown algorithm option\(s\) speed \(known: "):
        options_for("auto", {"speed": 4})


def test_options_from_cli_takes_the_flags_values():
    params = {"no_pyramid": True, "nextv": None, "better_nextv": None, "horizon_method": "hull",
              "sample_spacing": None, "exact_steps": 3, "curvature": True}
    given = options_from_cli(params)
    assert given == {"pyramid": False, "nextv": None, "better_nextv": None, "method": "hull",
                     "sample_spacing": None, "exact_steps": 3}
    assert params == {"curvature": True}
    assert options_from_cli({"no_pyramid": False})["pyramid"] is None


def test_generated_click_options_parse_as_the_hand_written_ones():
    """The example of the registry's use that the command line will follow: options generated
    from ``OPTIONS`` parse a command line into the same keywords as today's."""
    @click.command()
    @click.option("--algorithm", type=click.Choice(list(REGISTRY)), default="auto",
                  help=alg.algorithm_help())
    def cmd(algorithm, **kw):
        given = options_from_cli(kw)
        algorithm = algorithm_for(algorithm, given)
        print(algorithm, sorted(options_for(algorithm, given).items()))

    for _, opt in reversed(OPTIONS.values()):
        kind = {"choice": dict(type=click.Choice(opt.choices)),
                "int": dict(type=click.IntRange(min=opt.min)),
                "flag": dict(is_flag=True)}[opt.kind]
        cmd = click.option(opt.flag, opt.param, default=None, help=opt.help, **kind)(cmd)
    runner = click.testing.CliRunner()
    for args, out in [([], "auto []"), (["--no-pyramid"], "brute [('pyramid', False)]"),
                      (["--nextv", "quad"], "smap [('nextv', 'quad')]"),
                      (["--algorithm", "horizon", "--horizon-method", "hull"],
                       "horizon [('method', 'hull')]"),
                      (["--algorithm", "sweep", "--exact-steps", "3"],
                       "sweep [('exact_steps', 3)]")]:
        r = runner.invoke(cmd, args)
        assert r.exit_code == 0 and r.output.strip() == out, (args, r.output)
    r = runner.invoke(cmd, ["--sample-spacing", "0", "--algorithm", "horizon"])
    assert r.exit_code == 2
    r = runner.invoke(cmd, ["--exact-steps", "3"])
    assert isinstance(r.exception, UsageProblem)
    assert str(r.exception) == "--exact-steps applies to --algorithm sweep, not auto"


# ---------------------------------------------------------------------------------------------
# the GPU checks and the engine's facts

def test_gpu_unsupported_says_what_it_said():
    assert gpu_unsupported("bounds", {}) == (
        "--algorithm bounds has no GPU kernel (its sweep runs line after line); --algorithm auto "
        "or brute use the pyramid march on the GPU")
    assert gpu_unsupported("smap", {"better_nextv": True}) == (
        "--better-nextv has no GPU kernel (its per-beam stacks are as long as a beam)")
    assert gpu_unsupported("horizon", {"method": "hull"}) == (
        "--horizon-method hull has no GPU kernel (its per-line hulls are as long as a line)")
    for algorithm, options in [("auto", {}), ("brute", {"pyramid": False}), ("smap", {}),
                               ("smap", {"better_nextv": False, "nextv": "quad"}),
                               ("horizon", {"method": "scan", "sample_spacing": 3}),
                               ("sweep", {"exact_steps": 2}), ("nonesuch", {})]:
        assert gpu_unsupported(algorithm, options) is None, algorithm


def test_lookup_names_the_known_algorithms():
    assert alg.lookup("brute") is REGISTRY["brute"]
    with pytest.raises(HillshadeError, match="unknown algorithm 'fast'; choose one of auto, "
                                             "bounds, brute, smap, horizon, sweep"):
        alg.lookup("fast")


def test_planner_and_engine_read_the_registry():
    from hillshade_rt.engine.shader import field_method
    from hillshade_rt.engine.windows import bytes_per_cell
    assert {n: bytes_per_cell(n) for n in REGISTRY} == {
        "auto": 13, "bounds": 13, "brute": 13, "smap": 15, "horizon": 19, "sweep": 12}
    assert bytes_per_cell("nonesuch") == 20
    assert {n for n in REGISTRY if field_method(n, {}, False)} == {"auto", "bounds", "brute"}
    assert not field_method("brute", {"pyramid": False}, False)
