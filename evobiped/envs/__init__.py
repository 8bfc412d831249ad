"""Gymnasium environments (needs the ``gym`` extra: ``pip install 'evobiped[gym]'``).

Importing this module registers, in the ``evobiped`` namespace, one environment for every body of
:data:`evobiped.bodies.BODIES` that declares one (``Body.environment``): ``evobiped/<Name>Biped-v0``, its classes
``<Name>BipedEnv`` and, vector form, ``<Name>BipedVectorEnv`` (:func:`~.biped.env_classes`), e.g.
``evobiped/ReilBiped-v0`` (Reil & Husbands' 3D biped, PD target angles: :class:`ReilBipedEnv`,
:class:`ReilBipedVectorEnv`) and ``evobiped/TagaBiped-v0`` (Taga's sagittal biped, joint torques).  A body
registered later is registered by :func:`register_environments`.

``gymnasium.make("evobiped/ReilBiped-v0")`` gives one walker;
``gymnasium.make_vec("evobiped/ReilBiped-v0", num_envs=64, vectorization_mode="vector_entry_point")``
gives 64 stepped as one MuJoCo batch.
"""

try:
    import gymnasium
except ImportError:  # pragma: no cover - depends on the installation
    from ..core.errors import UserError

    raise UserError("the Gymnasium environments need gymnasium: pip install 'evobiped[gym]'") from None

from ..bodies import BODIES
from . import biped
from .biped import BipedEnv, BipedVectorEnv, env_classes
from .walkers import Walkers, env_id, env_name

__all__ = ["BipedEnv", "BipedVectorEnv", "ReilBipedEnv", "ReilBipedVectorEnv", "TagaBipedEnv", "TagaBipedVectorEnv",
           "Walkers", "env_classes", "env_id", "register_environments"]


def register_environments() -> list[str]:
    """Register the environment of every body of :data:`~evobiped.bodies.BODIES` that declares one and is not
    registered yet; returns the ids it registered."""
    added = []
    for body, cls in BODIES.items():
        if cls.environment is not None and env_id(body) not in gymnasium.registry:
            gymnasium.register(id=env_id(body), entry_point=f"evobiped.envs.biped:{env_name(body)}Env",
                               vector_entry_point=f"evobiped.envs.biped:{env_name(body)}VectorEnv")
            added.append(env_id(body))
    return added


def __getattr__(attr: str):
    """The environment classes by name (``ReilBipedEnv``, ...; :func:`evobiped.envs.biped.__getattr__`)."""
    return getattr(biped, attr)


register_environments()
