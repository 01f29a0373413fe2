"""Every SAN number and figure of docs/reproduction.md in one command.

    python experiments/san_all.py            # about an hour on 2 cores

Runs, in order and each as its own process (a failure stops the rest): Table 1 and the
usefulness bars (san_table1.py), the gait modes, the cart's fine-tuned modes and evolution
(san_gaits.py), Fig. 13's rough terrain, hill and friction with the node-delay claim
(san_robustness.py) and Fig. 10's pursuit (san_pursuit.py). Each writes its JSON and figures
under docs/figures/.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

SCRIPTS = ("san_table1.py", "san_gaits.py", "san_robustness.py", "san_pursuit.py")


def main() -> int:
    here = Path(__file__).resolve().parent
    for name in SCRIPTS:
        print(f"== {name}", flush=True)
        code = subprocess.call([sys.executable, str(here / name)])
        if code != 0:
            print(f"{name} failed with exit code {code}", file=sys.stderr)
            return code
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
