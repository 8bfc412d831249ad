"""The compiled kernel gives NumPy's numbers to the last bit (evobiped.core.kernel): NumPy's own loops found and
called, the CTRNN's compiled step against its NumPy step in every variant, whole episodes of the presets, and the
kernel option's bad values refused in one line."""

from __future__ import annotations

import dataclasses
import subprocess
import sys

import numpy as np
import pytest

from evobiped.core import kernel
from evobiped.core.errors import ConfigError

pytestmark = pytest.mark.skipif(kernel.unavailable() is not None, reason=str(kernel.unavailable()))


def bits(a) -> np.ndarray:
    return np.ascontiguousarray(a, float).view(np.int64)


@pytest.mark.parametrize("ufunc", [np.exp, np.arcsin])
def test_numpy_s_own_loop_is_found_and_called_from_compiled_code(ufunc):
    from evobiped.core.ufunc_calls import apply_loop

    x = np.random.default_rng(0).uniform(-1 if ufunc is np.arcsin else -50, 1 if ufunc is np.arcsin else 50, (37, 11))
    out = np.empty_like(x)
    apply_loop(kernel.ufunc_loop(ufunc), x, out)
    assert np.array_equal(bits(out), bits(ufunc(x)))


def _ctrnn(**options):
    from evobiped.controllers.ctrnn import CTRNN

    n_inputs = options.pop("n_inputs", 5)
    inputs = {"a": n_inputs} if n_inputs else {}
    return CTRNN(n_outputs=min(6, options.get("n_neurons", 10)), inputs=inputs, **options)


VARIANTS = {
    "paper": dict(n_inputs=0),
    "euler, senses, after": dict(outputs="after", normalise_inputs=True),
    "exponential, direct": dict(integration="exponential", time_constants=[0.02, 2.0], tau_scale="log", direct=True,
                                direct_scale=0.3, centre_crossing=True, motor="full"),
    "exponential, before, no inputs": dict(integration="exponential", time_constants=[0.02, 2.0], n_inputs=0),
    "one neuron": dict(n_neurons=1, integration="exponential", time_constants=[0.02, 2.0], direct=True),
    "one input, direct": dict(n_inputs=1, direct=True, outputs="after"),
}


@pytest.mark.parametrize("variant", list(VARIANTS))
def test_the_compiled_ctrnn_step_is_the_numpy_step_to_the_last_bit(variant):
    from evobiped.optimizers import GA, GAOptions

    ctrl = _ctrnn(**dict(VARIANTS[variant]))
    fast = ctrl.compiled()
    assert fast is not ctrl and fast.step is not ctrl.step
    genomes = GA(ctrl.layout, GAOptions(population=23), seed=3).ask()[0]
    genomes[0, : ctrl.n * ctrl.n] = 0.0  # a network without weights (one substep) beside random ones (many)
    params = ctrl.decode(genomes)
    if "substeps" in params:
        assert params["substeps"].min() < params["substeps"].max()  # rows that stop early and rows that go on
    rng = np.random.default_rng(5)
    a = b = ctrl.initial_state(params)
    for _ in range(40):
        x = rng.normal(size=(len(genomes), ctrl.n_inputs)) * 3
        a, out_a = ctrl.step(params, a, x)
        b, out_b = fast.step(params, b, x)
        assert np.array_equal(bits(a), bits(b)) and np.array_equal(bits(out_a), bits(out_b))
    assert np.ptp(a) > 0.1  # the networks moved


@pytest.mark.parametrize("preset", ["walker-ctrnn-walk", "paper"])
def test_a_preset_s_episode_is_the_same_with_either_kernel(preset):
    from evobiped.episode import Context
    from evobiped.flags import run_config
    from evobiped.optimizers import GA, GAOptions

    run = run_config(preset=preset)
    config = dataclasses.replace(run.episode.nominal(), seconds=1.0)
    context = Context(observe=True) if run.normalise.running else None
    results = []
    for name in ("numpy", "compiled"):
        ep = dataclasses.replace(config, kernel=name).build()
        assert ep.compiled == (name == "compiled")
        genomes = GA(ep.controller.layout, GAOptions(population=6), seed=2).ask()[0]
        results.append(ep.run(genomes, context=context))
    a, b = results
    for field in ("fitness", "end_position", "end_time"):
        assert np.array_equal(bits(getattr(a, field)), bits(getattr(b, field)))
    assert a.terms.keys() == b.terms.keys()
    for k in a.terms:
        assert np.array_equal(bits(a.terms[k]), bits(b.terms[k])), k


def test_the_kernel_is_written_to_files_only_where_it_was_chosen():
    from evobiped.episode import EpisodeConfig

    assert "kernel" not in EpisodeConfig().to_dict()
    assert EpisodeConfig(kernel="numpy").to_dict()["kernel"] == "numpy"


def test_an_unknown_kernel_is_one_config_error():
    from evobiped.episode import EpisodeConfig

    with pytest.raises(ConfigError, match="unknown kernel 'fast'"):
        EpisodeConfig(kernel="fast")


def test_a_compiled_kernel_that_cannot_run_says_what_brings_it(monkeypatch):
    monkeypatch.setattr(kernel, "unavailable", lambda: "the compiled kernel needs numba (pip install numba)")
    with pytest.raises(ConfigError, match="needs numba"):
        kernel.compiled("compiled")
    assert kernel.compiled("auto") is False and kernel.compiled("numpy") is False


def test_bench_refuses_an_unknown_kernel_in_one_line_exit_2():
    p = subprocess.run([sys.executable, "-m", "evobiped", "bench", "--quick", "--kernel", "fast"], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 2
    assert len(p.stderr.strip().splitlines()) == 1 and "kernel" in p.stderr


def test_auto_runs_numpy_where_the_address_space_is_limited_below_the_compilers_need():
    """Under ``ulimit -v 600000`` numba's compiler spun without end on a cold cache: ``auto`` then runs NumPy (the
    same numbers); an explicit ``compiled`` is still what was asked."""
    import subprocess
    import sys

    code = ("import resource; resource.setrlimit(resource.RLIMIT_AS, (3 * 2**30, 3 * 2**30)); "
            "from evobiped.core import kernel; print(kernel.compiled('auto'), kernel.compiled('numpy'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.stdout.split() == ["False", "False"], out.stderr
