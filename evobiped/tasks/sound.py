"""Sound sources on the ground plane and how the walker hears them (Reil & Husbands 2002, Sect. IV): each ear's
intensity, the ear signal s, the sources a config names or a generation draws.  The steer task
(:mod:`evobiped.tasks.steer`) reads them."""

from __future__ import annotations

import numpy as np

from ..core.errors import ConfigError
from ..core.options import given

#: the paper's (-3, -10) and (3, -10) in its x-z frame (walking towards -z), in ours (facing +x)
DEFAULT_SOURCES = ((10.0, 3.0), (10.0, -3.0))
#: m: a source nearer than this to the start (the origin) is refused
MIN_SOURCE_DISTANCE = 0.5


def ear_sites(model, task: str) -> tuple[int, int]:
    """The site ids of the body's ears (``left_ear``, ``right_ear``) in ``model``; ConfigError naming ``task`` for a
    body without them."""
    try:
        return model.site("left_ear").id, model.site("right_ear").id
    except KeyError:
        raise ConfigError(f"{task} task: the body has no ears (sites 'left_ear' and 'right_ear')") from None


def intensity(ear: np.ndarray, source: np.ndarray) -> np.ndarray:
    """I = 1 / |e - q|^2 (1/m^2) at ear ground positions ``(n, 2)`` from sources ``(n, 2)`` -> ``(n,)``."""
    return 1.0 / np.maximum(np.sum((ear - source) ** 2, axis=1), 1e-12)


def ear_signal(left: np.ndarray, right: np.ndarray, source: np.ndarray) -> np.ndarray:
    """s = (a - b) / (a + b) for ear ground positions ``(n, 2)`` and sources ``(n, 2)`` -> ``(n,)``."""
    a, b = intensity(left, source), intensity(right, source)
    return (a - b) / (a + b)


#: the farthest a source may be from the start (m)
MAX_SOURCE_DISTANCE = 1e4


def parse_sources(sources) -> np.ndarray:
    """``[[x, y], ...]`` in m -> ``(S, 2)``; ConfigError for anything else (e.g. a lone number)."""
    try:
        arr = np.array(sources, dtype=float)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.ndim != 2 or arr.shape[1] != 2 or len(arr) == 0 or not np.isfinite(arr).all():
        raise ConfigError(f"sources must be a list of [x, y] positions in m, e.g. [[10, 3], [10, -3]]; got {sources!r}")
    near = np.hypot(arr[:, 0], arr[:, 1]) < MIN_SOURCE_DISTANCE
    if near.any():
        x, y = arr[np.argmax(near)]
        raise ConfigError(f"the source ({x:g}, {y:g}) is at the walker's start (nearer than {MIN_SOURCE_DISTANCE:g} m "
                          "to the origin, where it starts): it could not walk towards it")
    far = np.hypot(arr[:, 0], arr[:, 1]) > MAX_SOURCE_DISTANCE
    if far.any():  # the ears' inverse squares underflow there: the sense would be 0/0
        x, y = arr[np.argmax(far)]
        raise ConfigError(f"the source ({x:g}, {y:g}) is farther than {MAX_SOURCE_DISTANCE:g} m from the walker's "
                          "start: its sound could not be told apart by the two ears")
    return arr


def with_sources(config, sources):
    """``config`` (an EpisodeConfig of the steer task) with these sources ``[[x, y], ...]`` m, one presentation
    each (fixed: they replace random sources drawn per generation); a commanded walker's (the command task) becomes the
    steer-command task's, its commands from its ears; ``sources`` None leaves it as it is.  UserError for an episode of
    another task."""
    import dataclasses

    from ..core.errors import UserError

    if sources is None:
        return config
    if config.task not in ("steer", "command", "steer-command"):
        raise UserError("--source applies to the steer task (--task steer) and to a commanded walker (--task "
                        f"command); this episode's task is {config.task!r}")
    options = {**given(config.task_options), "sources": [list(map(float, s)) for s in sources]}
    options.pop("random_sources", None)  # these sources, fixed, replace a distribution drawn per generation
    # a commanded walker hears them through the steering rule's commands (evobiped.tasks.steer_command)
    return dataclasses.replace(config, task_options=options, task="steer" if config.task == "steer"
                               else "steer-command")


def check_range(v) -> None:
    r = tuple(v) if isinstance(v, (list, tuple)) else None
    if r is None or len(r) not in (0, 2) or any(not isinstance(x, (int, float)) or isinstance(x, bool)
                                                or not np.isfinite(x)
                                                 for x in r) or (r and r[0] > r[1]):
        raise ConfigError(f"must be [] or [low, high] with low <= high (an empty range draws nothing), got {v!r}")


def draw_sources(options, key) -> np.ndarray | None:
    """The random sources ``(S, 2)`` m of generation key = (run seed, generation, ...) under ``options``
    (:class:`SteerOptions`); None without random sources."""
    S = int(options.random_sources)
    if not S or key is None:
        return None
    rng = np.random.default_rng([int(key[0]), int(key[1]), 0x50D])
    d = rng.uniform(*options.source_distance, S)
    a = np.radians(rng.uniform(*options.source_bearing, S))
    return np.stack([d * np.cos(a), d * np.sin(a)], axis=1)
