"""Fault campaign on ``evobiped evolve`` (and the commands that read its files), for a release check: runs
tests/fault_campaign.py, whose docstring and docs/faults.md say what it strikes and how each case is judged::

    python scripts/fault_campaign.py --repeat 50 --out /tmp/campaign      # about an hour on 2 cores
    python scripts/fault_campaign.py --repeat 2 --classes worker-sigkill group-kill
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.fault_campaign import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
