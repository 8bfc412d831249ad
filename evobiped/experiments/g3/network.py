"""The paper's quadruped G3 network (Pribe, Grossberg & Cohen 1997, eqs. 5-6, Figs. 2-3, Table 1) and its
published parameter sets.

Our readings of the text: quadruped channels are 0 = left fore, 1 = right fore,
2 = left hind, 3 = right hind (the paper's 1-4); the GO signal and every later
change of it reaches channel k ``lags[k]`` time units late ([0, sidelag,
hindlag, sidelag + hindlag], hindlag = cordlag) and a channel's input is 0
before the first arrival; Table 1's boundaries belong to the lower gait
(I = 0.35 is a pace); the modulation uses the command cell's (unlagged) I.
The cell equations are the core's (:mod:`evobiped.controllers.g3_network`);
:mod:`evobiped.experiments.g3.simulation` integrates this network under GO
schedules as the paper's figures do.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ...controllers.g3_network import CELLS, Shunting
from ...core.errors import ConfigError

#: quadruped channel names, in channel order
LIMBS = ("LF", "RF", "LH", "RH")


def quadruped_D(D0, D1, D2_af, D2_fa, D3_af, D3_fa) -> np.ndarray:
    """The 4x4 inhibition matrix of Figs. 2-3 from its six coefficients.

    Each argument is a scalar or a ``(B,)`` array; returns ``(..., 4, 4)``.
    "fore -> aft" is from a fore channel (j) onto a hind channel (i).
    """
    a = np.broadcast_arrays(*(np.asarray(v, float) for v in (D0, D1, D2_af, D2_fa, D3_af, D3_fa)))
    D0, D1, D2_af, D2_fa, D3_af, D3_fa = a
    D = np.zeros(a[0].shape + (4, 4))
    LF, RF, LH, RH = range(4)
    for i in range(4):
        D[..., i, i] = D0
    for i, j in ((LF, RF), (RF, LF), (LH, RH), (RH, LH)):
        D[..., i, j] = D1
    for fore, hind in ((LF, LH), (RF, RH)):  # ipsilateral
        D[..., hind, fore] = D2_fa
        D[..., fore, hind] = D2_af
    for fore, hind in ((LF, RH), (RF, LH)):  # contralateral
        D[..., hind, fore] = D3_fa
        D[..., fore, hind] = D3_af
    return D


#: Table 1: (upper bound of I, inclusive; D0, D1, D2 aft->fore, D2 fore->aft, D3 aft->fore, D3 fore->aft)
TABLE_1 = (
    ("walk", 0.17, (1.0, 0.3, 0.0, 0.3, 0.3, 0.0)),
    ("trot", 0.25, (1.0, 0.3, 0.3, 0.3, 0.55, 0.55)),
    ("pace", 0.35, (1.0, 0.3, 0.55, 0.55, 0.3, 0.3)),
    ("gallop", np.inf, (1.0, 0.55, 0.3, 0.3, 0.3, 0.3)),
)


def table1_gait(I: np.ndarray) -> np.ndarray:
    """Index of the Table 1 column for each I (boundaries belong to the lower gait)."""
    bounds = np.array([row[1] for row in TABLE_1[:-1]])
    return np.searchsorted(bounds, np.asarray(I, float) - 1e-12, side="left")


def table1_D(I: np.ndarray) -> np.ndarray:
    """Modulated inhibition D_ij h_ij(I) of eq. (5) for each I: ``(..., 4, 4)``."""
    coef = np.array([row[2] for row in TABLE_1])[table1_gait(I)]
    return quadruped_D(*np.moveaxis(coef, -1, 0))


@dataclass(frozen=True, kw_only=True)
class G3Network:
    """An N-channel G3 network: constants, inhibition, GO lags and input asymmetry.

    D: ``(N, N)`` fixed inhibition, or None with ``modulated=True`` (Table 1, N = 4).
    lags: ``(N,)`` arrival lag of every GO change per channel (time units).
    delta: ``(N,)`` added to a channel's input once the GO signal has reached it (Fig. 7).
    """

    cells: Shunting = field(default_factory=Shunting)
    D: tuple | None = None
    modulated: bool = False
    lags: tuple = (0.0, 0.0, 0.0, 0.0)
    delta: tuple = (0.0, 0.0, 0.0, 0.0)

    def __post_init__(self):
        n = len(self.lags)
        if n < 1 or len(self.delta) != n:
            raise ConfigError("G3: lags and delta need one value per channel (at least one channel)")
        if min(self.lags) < 0:
            raise ConfigError(f"G3: lags must be >= 0, got {self.lags}")
        if self.modulated:
            if n != 4:
                raise ConfigError("G3: Table 1 modulation needs the 4 quadruped channels")
        elif self.D is None or np.shape(self.D) != (n, n):
            raise ConfigError(f"G3: D must be {n}x{n}")

    @property
    def n(self) -> int:
        return len(self.lags)

    def inhibition(self, I_command: np.ndarray) -> np.ndarray:
        """``(B, N, N)`` inhibition for the command GO level ``(B,)``."""
        if self.modulated:
            return table1_D(I_command)
        return np.broadcast_to(np.asarray(self.D, float), (len(I_command), self.n, self.n))


@dataclass(frozen=True, kw_only=True)
class Preset:
    """A published parameter set: the network, its GO level(s) and run length.

    go: the GO level(s) the paper shows; t_max: the paper's run length; t_run:
    the length we integrate (longer, to measure steady states).
    """

    name: str
    source: str
    network: G3Network
    go: tuple[float, ...]
    t_max: float
    t_run: float


def _lags(cordlag: float, sidelag: float) -> tuple:
    return (0.0, sidelag, cordlag, sidelag + cordlag)


_FIG4_D = quadruped_D(0.8, 0.185, 0.0, 0.15, 0.15, 0.0)
_FIG5_D = quadruped_D(0.95, 0.255, 0.3, 0.3, 0.3, 0.3)
_FIG4 = G3Network(cells=CELLS["fig4"], D=tuple(map(tuple, _FIG4_D)), lags=_lags(0.0025, 0.001))
_FIG5A = G3Network(cells=CELLS["fig5a"], D=tuple(map(tuple, _FIG5_D)), lags=_lags(0.2, 0.05))
_FIG7 = G3Network(cells=CELLS["fig7"], modulated=True, lags=_lags(0.0, 0.0), delta=(0.001, 0.0, 0.0, 0.0))
_FIG8A = G3Network(cells=CELLS["fig8a"], modulated=True, lags=_lags(0.00025, 0.0001))

PRESETS: dict[str, Preset] = {
    p.name: p
    for p in (
        Preset(name="fig4", source="Fig. 4: a walk at I = 0.1", network=_FIG4, go=(0.1,), t_max=60.0, t_run=120.0),
        Preset(name="fig5a", source="Fig. 5A: symmetric, unmodulated; trot, pace, gallop by I", network=_FIG5A,
               go=(0.1, 0.2, 0.3, 0.4), t_max=60.0, t_run=120.0),
        Preset(name="fig5b", source="Fig. 5B: Fig. 5A with B = 1.05 (the pace disappears)",
               network=replace(_FIG5A, cells=CELLS["fig5b"]), go=(0.1, 0.2, 0.3, 0.4), t_max=60.0, t_run=120.0),
        Preset(name="fig7", source="Fig. 7: Table 1 modulation, input asymmetry delta = 0.001 on LF", network=_FIG7,
               go=(0.1, 0.2, 0.3, 0.4), t_max=30.0, t_run=120.0),
        Preset(name="fig8a", source="Fig. 8A/9: Table 1 modulation, cordlag 0.00025, sidelag 0.0001", network=_FIG8A,
               go=(0.1, 0.2, 0.3, 0.4), t_max=30.0, t_run=120.0),
        Preset(name="human", source="Sect. 6, Figs. 10-11: Fig. 4 parameters; walk at I = 0.1, run at I = 0.15",
               network=replace(_FIG4, cells=CELLS["human"]), go=(0.1, 0.15), t_max=60.0, t_run=120.0),
        Preset(
            name="human-lagged",
            source="TUNED, not published: Fig. 4 parameters with Fig. 5A's GO lags (cordlag 0.2, sidelag 0.05); the "
                   "run keeps the walk's phases when entered from the walk",
            network=replace(_FIG4, cells=CELLS["human-lagged"], lags=_lags(0.2, 0.05)),
            go=(0.1, 0.2),
            t_max=60.0,
            t_run=120.0,
        ),
    )
}


def preset(name: str) -> Preset:
    """The preset called ``name``; ConfigError naming the choices otherwise."""
    try:
        return PRESETS[name]
    except KeyError:
        raise ConfigError(f"unknown G3 preset {name!r} (choose from {', '.join(PRESETS)})") from None
