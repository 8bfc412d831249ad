import numpy as np
import pytest

from evobiped.cli import main


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def random_genomes(layout, n, seed=0):
    """Genomes drawn from the layout's initialisation Gaussians, clipped to bounds."""
    r = np.random.default_rng(seed)
    return layout.sample(r, n)


def cli(*args) -> int:
    """Exit status of ``evobiped ARGS`` run in this process (argument errors exit via SystemExit)."""
    try:
        return main([str(a) for a in args])
    except SystemExit as exc:
        return exc.code
