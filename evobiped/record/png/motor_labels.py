"""What a walker's motor outputs are and what each is called, for the figures: neuron outputs in [0, 1], PD
target angles (rad) or torques (N m); each by its actuator, or in the stance frame by its leg role."""

from __future__ import annotations

import numpy as np

from ..trajectory import Trajectory


def _motor_quantity(traj: Trajectory) -> tuple[bool, bool, str]:
    """(outputs are neuron outputs in [0, 1], commands are PD target angles, the y-axis label)."""
    motor = traj.neurons[:, : traj.n_motor]
    unit = motor.size == 0 or (np.nanmin(motor) >= 0.0 and np.nanmax(motor) <= 1.0)  # else e.g. angles, torques
    target = traj.action_kind == "position"  # PD target angles
    quantity = ("output (0-1)" if unit else "target angle (rad)" if target else "torque (N m)"
                if traj.action_kind == "torque" else "command")
    return unit, target, quantity


def motor_file(traj: Trajectory) -> str:
    """The motor figure's file name, for what it shows: ``motor_neurons.png`` (a network's motor neurons),
    ``joint_targets.png`` (a controller without neurons setting PD targets), else ``motor_outputs.png``."""
    unit, target, _ = _motor_quantity(traj)
    return "motor_neurons.png" if unit else "joint_targets.png" if target else "motor_outputs.png"


def _motor_label(traj: Trajectory, i: int) -> str:
    """Motor output ``i``'s name: its actuator, or in the stance frame its joint on the stance (first half) or swing
    leg."""
    if i >= len(traj.actuator_names):
        return f"output {i + 1}"
    name = traj.actuator_names[i]
    if not traj.stance_frame:
        return name
    half = len(traj.actuator_names) // 2
    role = name.split("_", 1)[1] if "_" in name else name
    return f"{'stance' if i < half else 'swing'} {role}"
