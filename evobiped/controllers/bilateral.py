"""One set of genes for both legs of a rhythm generator in the body's frame (the ``symmetric`` option).

A rhythm generator keeps its oscillators on the body's legs (a stance frame would swap them at every touch-down),
so the stance frame's prior, one set of weights serving both legs, is given to it here instead: the genes set the
first leg's units (the body's actuators ``first``, ``(n/2,)``) and the second leg's unit for joint j is the mirror
image of the first leg's, by the body's declared mirror (:mod:`evobiped.interface.frame`): the action mirror
``perm``/``sign`` over the ``n`` actuators and the input mirror over the ``k`` inputs, x'_i = s_i x_{p_i} (the legs'
columns swapped, lateral readings negated).  So a unit of the second leg reads the mirrored senses through the first
leg's gains, (K x)_{perm j} = K_j . x', with the same time constants, amplitudes and posture.
"""

from __future__ import annotations

import numpy as np

from ..core.errors import ConfigError


class Bilateral:
    """The mirror that spreads first-leg genes over both legs: ``actions`` (perm ``(n,)``, sign ``(n,)``) of the
    body's actuators, ``inputs`` (perm ``(k,)``, sign ``(k,)``) of the controller's inputs."""

    def __init__(self, actions: tuple, inputs: tuple, *, what: str):
        perm, sign = (np.asarray(a) for a in actions)
        if np.any(sign != 1):
            raise ConfigError(f"{what}: symmetric needs a body whose mirrored joints share their signs (its actuator "
                              "mirror negates one)")
        n = len(perm)
        first = []
        for j in range(n):  # the first of each mirrored pair, in action order
            if j not in first and perm[j] not in first and perm[j] != j:
                first.append(j)
        if 2 * len(first) != n:
            raise ConfigError(f"{what}: symmetric needs every actuator paired with one on the other leg")
        self.first = np.array(first, int)
        self.second = perm[self.first]
        self.n = n
        self.input_perm, self.input_sign = np.asarray(inputs[0], int), np.asarray(inputs[1], float)

    def units(self, v: np.ndarray) -> np.ndarray:
        """Per-unit genes of the first leg ``(P, n/2)`` -> both legs' ``(P, n)``, the second leg's the same."""
        out = np.empty((v.shape[0], self.n))
        out[:, self.first], out[:, self.second] = v, v
        return out

    def gains(self, K: np.ndarray) -> np.ndarray:
        """Input gains of the first leg's units ``(P, n/2, k)`` -> both legs' ``(P, n, k)``: row ``second[j]`` reads
        the mirrored inputs through row j, K_full[second j, perm_i] = K[j, i] s_i."""
        out = np.empty((K.shape[0], self.n, K.shape[2]))
        out[:, self.first] = K
        mirrored = np.empty_like(K)
        mirrored[:, :, self.input_perm] = K * self.input_sign
        out[:, self.second] = mirrored
        return out

    def couplings(self, D: np.ndarray) -> np.ndarray:
        """A unit-to-unit matrix whose first-leg rows are given, ``rows`` ``(P, n/2, n)`` (row j: what reaches unit
        ``first[j]`` from every unit) -> ``(P, n, n)`` with D[perm a, perm b] = D[a, b]."""
        perm = np.empty(self.n, int)
        perm[self.first], perm[self.second] = self.second, self.first
        out = np.empty((D.shape[0], self.n, self.n))
        out[:, self.first] = D
        out[:, self.second[:, None], perm[None, :]] = D
        return out
