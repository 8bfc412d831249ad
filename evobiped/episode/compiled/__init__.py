"""The episode in compiled code (the ``kernel`` option, :mod:`evobiped.core.kernel`): :mod:`.whole` runs a whole
episode of the parts it knows in one numba call per batch, without the GIL.  Importing a module here imports numba."""
