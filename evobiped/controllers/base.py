"""What every controller provides: a genome layout and a vectorised step.

A controller is structure only.  Its parameters (decoded from a ``(P, G)``
genome array) and its state (``(P, ...)`` arrays) are separate, and ``step`` is a
pure function ``(params, state, inputs) -> (state, outputs)`` over the whole
population, so one implementation serves a replay (P = 1) and a batch (P = 50+).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, ClassVar, Literal

import numpy as np

from ..interface.contract import Needs
from ..core.errors import ConfigError
from ..interface.frame import FRAMES
from ..interface.genome import GenomeLayout
from ..core.options import constructor_options, option

#: the longest control latency, in control ticks
MAX_LATENCY = 100


def _norm_table(v) -> None:
    """A normaliser table: ``mean`` and ``std`` lists of one length (std > 0), a ``count`` >= 0."""
    ok = isinstance(v, dict) and set(v) <= {"mean", "std", "count"} and {"mean", "std"} <= set(v)
    if ok:
        m, s = v["mean"], v["std"]
        ok = isinstance(m, list) and isinstance(s, list) and len(m) == len(s) and all(
            isinstance(x, (int, float)) and not isinstance(x, bool) and np.isfinite(x) for x in m
                + s) and all(x > 0 for x in s)
        ok = ok and (isinstance(v.get("count", 0), (int, float)) and not isinstance(v.get("count", 0), bool)
                     and v.get("count", 0) >= 0)
    if not ok:
        raise ConfigError("must be a table {mean = [...], std = [...], count = n} with one finite mean and one std > 0 "
                          "per input")


@dataclass(frozen=True, kw_only=True)
class ControllerOptions:
    """What every controller takes, handled by the episode (each controller's ``Options`` subclasses this):
    the sensors to feed, gene-block overrides and control latency."""

    inputs: list | None = option(None, "sensor names to feed, replacing the controller's default choice")
    genes: dict = option({}, "gene-block overrides (bounds, initialisation, mutation; see GenomeLayout.with_overrides)")
    latency: int = option(0, "control ticks by which its actions reach the body late (the first action is held "
                             "meanwhile)", unit="control ticks", low=0, high=MAX_LATENCY, integer=True)
    frame: str = option("body", "`body`: senses and actions as the body gives them; `stance`: mirrored so the stance "
                                "leg is always the first (one set of weights serves both legs; the body must declare "
                                "its mirror)", choices=FRAMES)
    input_norm: dict | None = option(None, "the observation normaliser the genome was evolved with, {mean = [...], std "
                                           "= [...], count = n} over its inputs (written by a run that normalises; "
                                           "replaces the declared standing values and scales)", check=_norm_table)


#: the options of :class:`ControllerOptions`, every controller's (the README's tables list each controller's own)
GENERIC_CONTROLLER_OPTIONS = ("inputs", "genes", "latency", "frame", "input_norm")


class Controller(ABC):
    """Base class; subclasses are registered in :data:`evobiped.controllers.CONTROLLERS`."""

    name: ClassVar[str]
    #: a paragraph docs/usage.md gives above its generated option table (markdown; "": none)
    docs_note: ClassVar[str] = ""
    #: how :func:`evobiped.interface.mapping.to_action` reads the outputs: "unit": in [0, 1] spanning the joint's range;
    #: "centred": in [0, 1] with 0.5 at 0 rad; "signed": real-valued, centred on 0; "angle": joint targets in rad
    output_kind: ClassVar[Literal["unit", "centred", "centred_full", "signed", "angle"]]

    #: number of motor outputs (= the body's actuators)
    n_outputs: int
    #: names of the sensor arrays (body or task) concatenated into ``inputs``
    input_names: tuple[str, ...] = ()
    #: control period in s, or None to step at every physics step
    dt: float | None
    #: whether the episode hands it its inputs normalised (``Needs.normalised``), and with what:
    #: ``(centre (k,), scale (k,))`` set by the episode; None: raw readings
    normalises_inputs: bool = False
    input_norm: tuple | None = None
    # : the stance frame the episode reads its senses and writes its actions in (:mod:`evobiped.interface.frame`; None:
    # the body's)
    frame: Any = None

    #: the width of the input vector it reads (set by its constructor), whose senses a run's running normaliser
    #: learns (``EpisodeResult.senses``); None: it reads no such vector
    n_inputs: int | None = None
    # : the controller's options (a subclass of :class:`ControllerOptions` adding its own
    # :func:`evobiped.core.options.option` fields)
    Options: ClassVar[type] = ControllerOptions

    @classmethod
    def needs(cls, options) -> Needs:
        """What this controller, with these options (its parsed ``Options``), needs of its body and task (see
        :mod:`evobiped.interface.contract`); the episode checks it once and constructs the controller with the wiring:
        ``cls(options, n_outputs=..., inputs={sensor: width}, actuators=body.actuators)``."""
        return Needs()

    @classmethod
    def own_options(cls, options: Any, given: dict) -> Any:
        """A constructor's options: the parsed ``options`` object, or the keyword settings ``given`` (Python use)."""
        return constructor_options(cls.Options, options, given, f"{cls.name} controller_options")

    def bound(self, dt: float) -> "Controller":
        """This controller stepping at control period ``dt`` (s; the physics step when ``dt`` is None):
        itself where the period makes no difference, else a copy (this one is left unchanged)."""
        return self

    def reframe(self, state: Any, flip: np.ndarray) -> Any:
        """``state`` expressed in this tick's stance frame, ``flip`` ``(P,)`` bool the rows whose second leg stands
        (called before :meth:`step` where ``frame = "stance"``): itself for a controller whose state has no legs; a
        rhythm generator swaps its legs' units on the rows whose frame changed, so each leg's oscillator keeps
        running on that leg while the genes it follows are the stance or the swing leg's."""
        return state

    def compiled(self) -> "Controller":
        """This controller with its step in compiled code giving the same numbers to the last bit (the episode's
        ``kernel``, :mod:`evobiped.core.kernel`): a copy, or itself where it has no compiled step."""
        return self

    @property
    @abstractmethod
    def layout(self) -> GenomeLayout:
        """The genome layout: blocks, bounds, init and mutation distributions."""

    def override_genes(self, genes: dict) -> None:
        """Replace bounds/initialisation/mutation of named gene blocks (the ``genes`` controller option).

        Subclasses keep their layout in ``self._layout``.
        """
        self._layout = self.layout.with_overrides(genes)

    def decode(self, genomes: np.ndarray) -> dict[str, np.ndarray]:
        """``(P, G)`` genomes -> parameter arrays with leading dimension P.

        Validates the genomes first (GenomeError on a bad one).
        """
        g = self.layout.validate(genomes)
        return {k: v.copy() for k, v in self.layout.split(g).items()}

    @abstractmethod
    def initial_state(self, params: dict[str, np.ndarray]) -> Any:
        """The state at t = 0 for every individual."""

    @abstractmethod
    def step(self, params: dict[str, np.ndarray], state: Any, inputs: np.ndarray) -> tuple[Any, np.ndarray]:
        """Advance one control period.  ``inputs`` ``(P, n_in)`` -> ``(state, outputs (P, n_outputs))``."""

    @abstractmethod
    def neuron_outputs(self, params: dict[str, np.ndarray], state: Any) -> np.ndarray:
        """Every neuron's output ``(P, n_neurons)``, motor neurons first (for recording)."""
