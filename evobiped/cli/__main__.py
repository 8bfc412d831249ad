"""``python -m evobiped.cli``: the ``evobiped`` command."""

import sys

from . import main

sys.exit(main())
