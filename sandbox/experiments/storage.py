"""The files of a sweep, one pair per finished trial, under ``DIR/trials/<case>/``:

- ``seed-<seed>.csv``: both metrics (and the health counts) every
  ``metrics_every`` steps and at the last step;
- ``seed-<seed>.json``: the full configuration, seed, timing and the final
  layout of boxes and robots. It is written last and marks the trial done.

Re-running the same sweep skips trials whose JSON file is there, so an
interrupted sweep loses at most the trials that were running.
"""

from __future__ import annotations

import contextlib
import json
import os
import sys
from pathlib import Path
from typing import Iterator

from filelock import FileLock, Timeout

from sandbox.experiments.trials import SweepError, Trial, slug
from sandbox.model.metrics import SampleWriter, read_samples

TRIALS_DIR = "trials"
FAILURES_FILE = "failures.json"
SWEEP_FILE = "sweep.json"  # the sweep's cases and command (see sweep.write_meta)
LOCK_FILE = ".sweep.lock"  # held by the sweep writing to the folder (ResultStore.lock)


def write_whole(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` whole or not at all: into ``<path>.tmp``, then renamed over it, so a reader
    (or a sweep resuming after a kill) never sees half a file."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


class ResultStore:
    """The trial files of a sweep under ``DIR/trials``."""

    def __init__(self, out: str | Path):
        self.root = Path(out)
        self.trials_dir = self.root / TRIALS_DIR

    def paths(self, case: str, seed: int) -> tuple[Path, Path]:
        folder = self.trials_dir / slug(case)
        return folder / f"seed-{seed}.csv", folder / f"seed-{seed}.json"

    def check_writable(self) -> None:
        try:
            self.trials_dir.mkdir(parents=True, exist_ok=True)
            probe = self.root / ".write-test"
            probe.write_text("ok")
            probe.unlink()
        except OSError as exc:
            raise SweepError(f"cannot write results to {self.root}: {exc.strerror or exc}") from None

    @contextlib.contextmanager
    def lock(self) -> Iterator[None]:
        """Refuse a second sweep into the same folder while one runs (it would repeat the same trials).

        The operating system's lock on :data:`LOCK_FILE` (through filelock): it ends with the process that
        holds it, killed or not, so no lock is ever left stale, and there is no stale lock to clear while
        another sweep takes it. The file itself stays, empty (removing it would let two sweeps lock two
        files of one name)."""
        lock = FileLock(self.root / LOCK_FILE, timeout=0)
        try:
            lock.acquire()
        except Timeout:
            raise SweepError(f"another sweep is writing to {self.root}; wait for it to finish or stop it") from None
        try:
            yield
        finally:
            lock.release()

    def is_done(self, trial: Trial) -> bool:
        """True when the trial's files are there and were made with the same configuration."""
        csv_path, json_path = self.paths(trial.case, trial.seed)
        if not (json_path.is_file() and csv_path.is_file()):
            return False
        try:
            stored = json.loads(json_path.read_text())["config"]
        except (OSError, ValueError, KeyError, TypeError):
            return False  # a torn or foreign file: run the trial again
        if stored != trial.config:
            diff = sorted(k for k in set(stored) | set(trial.config) if stored.get(k) != trial.config.get(k))
            shown = ", ".join(f"{k} {stored.get(k)!r} -> {trial.config.get(k)!r}" for k in diff[:3])
            raise SweepError(f"{self.root} already holds case {trial.case!r} seed {trial.seed} run with other "
                             f"parameters ({shown}); use another --out or delete that folder")
        return True

    def save(self, case: str, result: dict) -> None:
        csv_path, json_path = self.paths(case, result["seed"])
        csv_path.parent.mkdir(parents=True, exist_ok=True)
        tmp = csv_path.with_suffix(".csv.tmp")
        with tmp.open("w", newline="") as fh:
            writer = SampleWriter(fh, leading=("case", "seed"))
            for sample in result["samples"]:
                writer.write(sample, case=case, seed=result["seed"])
        os.replace(tmp, csv_path)
        meta = {k: v for k, v in result.items() if k != "samples"}
        meta["case"] = case
        write_whole(json_path, json.dumps(meta, separators=(",", ":")))  # last: marks the trial done

    def load(self) -> list[dict]:
        """Every finished trial: its JSON record plus ``samples`` (dict of numpy arrays) from its CSV."""
        results = []
        for json_path in sorted(self.trials_dir.glob("*/seed-*.json")):
            csv_path = json_path.with_suffix(".csv")
            try:
                meta = json.loads(json_path.read_text())
                meta["samples"] = read_samples(csv_path)
            except (OSError, ValueError, KeyError) as exc:
                print(f"warning: skipping unreadable trial {json_path}: {exc}", file=sys.stderr)
                continue
            results.append(meta)
        return results

    def save_failures(self, failures: list[dict]) -> None:
        path = self.root / FAILURES_FILE
        if failures:
            path.write_text(json.dumps(failures, indent=1))
        elif path.exists():
            path.unlink()

    def load_failures(self) -> list[dict]:
        path = self.root / FAILURES_FILE
        try:
            return json.loads(path.read_text()) if path.is_file() else []
        except (OSError, ValueError):
            return []


def load_meta(out: Path) -> dict:
    path = Path(out) / SWEEP_FILE
    if not path.is_file():
        return {}
    try:
        return json.loads(path.read_text())
    except ValueError:
        raise SweepError(f"{path} is not valid JSON; delete it and re-run the sweep command") from None
