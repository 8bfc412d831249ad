"""Gymnasium environments (needs the ``gym`` extra: ``pip install 'evobiped[gym]'``).

Importing this module registers, in the ``evobiped`` namespace:

* ``evobiped/ReilBiped-v0``: Reil & Husbands' 3D biped, PD target angles
  (:class:`ReilBipedEnv`, vector form :class:`ReilBipedVectorEnv`);
* ``evobiped/TagaBiped-v0``: Taga's sagittal biped, joint torques
  (:class:`TagaBipedEnv`, vector form :class:`TagaBipedVectorEnv`).

``gymnasium.make("evobiped/ReilBiped-v0")`` gives one walker;
``gymnasium.make_vec("evobiped/ReilBiped-v0", num_envs=64, vectorization_mode="vector_entry_point")``
gives 64 stepped as one MuJoCo batch.
"""

try:
    import gymnasium
except ImportError:  # pragma: no cover - depends on the installation
    from ..core.errors import UserError

    raise UserError("the Gymnasium environments need gymnasium: pip install 'evobiped[gym]'") from None

from .biped import BipedEnv, BipedVectorEnv, ReilBipedEnv, ReilBipedVectorEnv, TagaBipedEnv, TagaBipedVectorEnv
from .walkers import Walkers

__all__ = ["BipedEnv", "BipedVectorEnv", "ReilBipedEnv", "ReilBipedVectorEnv", "TagaBipedEnv", "TagaBipedVectorEnv", "Walkers"]

for _name, _env, _vec in (("ReilBiped", ReilBipedEnv, ReilBipedVectorEnv), ("TagaBiped", TagaBipedEnv, TagaBipedVectorEnv)):
    _id = f"evobiped/{_name}-v0"
    if _id not in gymnasium.registry:
        gymnasium.register(id=_id, entry_point=f"evobiped.envs.biped:{_env.__name__}",
                           vector_entry_point=f"evobiped.envs.biped:{_vec.__name__}")
