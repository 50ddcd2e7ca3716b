"""Golden state digests: short seeded runs whose exact state must not move unnoticed.

``python -m tests.golden.runs`` checks every run listed in ``digests.json``
(the seven cases, open loop and chase, seed 3) and prints what differs;
``--update`` rewrites the file. Change a digest only knowingly, in the same
commit as the change that moves it, and say why in its message.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from sandbox.model.config import CASES, Config
from sandbox.model.simulation import Simulation

DIGESTS = Path(__file__).with_name("digests.json")
SEED = 3

#: The runs ``pytest`` checks (tests/model/test_golden.py): name -> steps. Open loop on three cases
#: (flare; switch and no corners, the switch acting only once the first dilation is under way, near
#: step 8,200), chase on two. A name ending in ``/N`` has the controller update every N steps instead
#: of 100: the star's switch then acts near step 2,125, the same code in a third of the steps.
QUICK = {"circle": 3000, "square-flare-switch": 3000, "star-switch-nocorners": 9000,
         "star-switch-nocorners/25": 3000, "circle+chase": 3000, "star-switch+chase": 3000}
#: Of those, the long run that the fast loop leaves to the full suite (``slow``): the /25 run beside it
#: covers the same strategies in the fast loop.
LONG = {"star-switch-nocorners"}
#: Every case, open loop and chase, as refactors check them.
FULL = {**{case: 6000 for case in CASES}, **{f"{case}+chase": 6000 for case in CASES}}


def run_digest(name: str, steps: int) -> str:
    name, _, every = name.partition("/")
    case, _, chase = name.partition("+")
    config = Config().replace(**CASES[case], seed=SEED, chase=2.0 if chase else 0.0)
    if every:
        config = config.replace(update_every=int(every))
    sim = Simulation(config)
    sim.step(steps)
    return sim.state_digest()


def key(name: str, steps: int) -> str:
    return f"{name} seed {SEED} {steps} steps"


def stored() -> dict[str, str]:
    return json.loads(DIGESTS.read_text())


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--update", action="store_true", help="rewrite digests.json with today's digests")
    parser.add_argument("--quick", action="store_true", help="only the runs the tests check")
    args = parser.parse_args(argv)
    runs = list(QUICK.items()) + ([] if args.quick else list(FULL.items()))
    known = stored() if DIGESTS.exists() else {}
    found: dict[str, str] = {}
    moved = 0
    for name, steps in runs:
        started = time.perf_counter()
        found[key(name, steps)] = digest = run_digest(name, steps)
        was = known.get(key(name, steps))
        status = "same" if digest == was else ("new" if was is None else f"MOVED (was {was})")
        moved += status.startswith("MOVED")
        print(f"{key(name, steps):45s} {digest}  {status}  {time.perf_counter() - started:.1f} s", flush=True)
    if args.update:
        DIGESTS.write_text(json.dumps({**known, **found}, indent=1, sort_keys=True) + "\n")
        print(f"wrote {DIGESTS}")
    return 1 if moved and not args.update else 0


if __name__ == "__main__":
    sys.exit(main())
