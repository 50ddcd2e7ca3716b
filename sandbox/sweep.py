"""Running many independent trials: the trial function, result files, resume, executors.

A *trial* is one simulation run of one case with one seed. :func:`run_trial`
is a top-level function of plain data, so it can be shipped to local worker
processes or to a Dask cluster alike. Each finished trial is written at once
under ``DIR/trials/<case>/`` as

- ``seed-<seed>.csv``: both metrics (and the health counts) every
  ``metrics_every`` steps and at the last step;
- ``seed-<seed>.json``: the full configuration, seed, timing and the final
  layout of boxes and robots. It is written last and marks the trial done.

Re-running the same sweep skips trials whose JSON file is there, so an
interrupted sweep loses at most the trials that were running.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import csv
import json
import multiprocessing
import os
import re
import signal
import socket
import sys
import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from .config import Config
from .metrics import SAMPLE_FIELDS

METRICS = ("fraction_in_goal", "mean_outside_distance")
TRIALS_DIR = "trials"
FAILURES_FILE = "failures.json"
ATTEMPTS = 2  # a failing trial is retried once
DASK_CONNECT_TIMEOUT = "15s"


class SweepError(Exception):
    """A problem with a sweep a user can fix (shown as one line)."""


# ---------------------------------------------------------------------------
# The trial itself: runs in a worker.


def run_trial(config: dict, seed: int, steps: int, shape: list | None) -> dict:
    """Run one trial and return its samples, configuration and final layout.

    ``config`` is a full configuration as from ``Config.to_dict()``; ``shape``
    the goal polygon's vertices (None for the circle), resolved by the caller
    so workers need not see the user's shape files.
    """
    from .simulation import Simulation  # imported in the worker

    cfg = Config(**config).replace(seed=int(seed), steps=int(steps))
    start, cpu = time.perf_counter(), time.process_time()
    sim = Simulation(cfg, shape=None if shape is None else np.asarray(shape, dtype=float))
    sim.step(cfg.steps)
    if sim.has_nan():
        raise RuntimeError(f"the simulation produced NaN (seed {seed})")
    samples = [s.to_dict() for s in sim.history]
    if samples[-1]["step"] != sim.steps_done:
        samples.append(sim.measure().to_dict())
    return {
        "config": cfg.to_dict(),
        "seed": cfg.seed,
        "steps": cfg.steps,
        "seconds": round(time.perf_counter() - start, 3),
        "cpu_seconds": round(time.process_time() - cpu, 3),
        "host": socket.gethostname(),
        "samples": samples,
        "final": {
            "box_positions": np.round(sim.box_positions, 4).tolist(),
            "box_angles": np.round(sim.box_angles, 4).tolist(),
            "box_in_goal": sim.box_in_goal.astype(int).tolist(),
            "robot_positions": np.round(sim.robot_positions, 4).tolist(),
            "goal_outline": np.round(sim.goal.outline(), 5).tolist(),
        },
    }


# ---------------------------------------------------------------------------
# What to run.


@dataclass(frozen=True)
class Trial:
    case: str
    seed: int
    config: dict = field(compare=False, hash=False)  # full config dict, seed and steps included
    shape: list | None = field(default=None, compare=False, hash=False)

    @property
    def name(self) -> str:
        return f"{self.case} seed {self.seed}"


def slug(label: str) -> str:
    """A file-system-safe folder name for a case label."""
    return re.sub(r"[^A-Za-z0-9._=+-]+", "_", label).strip("_") or "case"


# ---------------------------------------------------------------------------
# Result files.


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
        """Refuse a second sweep into the same folder while one runs (it would repeat the same trials)."""
        path = self.root / ".sweep.lock"
        me = f"{socket.gethostname()} {os.getpid()}"
        for _ in range(2):
            try:
                fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                try:
                    host, pid = path.read_text().split()
                except (OSError, ValueError):
                    host, pid = "", "0"
                if host == socket.gethostname() and not _alive(int(pid)):
                    path.unlink(missing_ok=True)  # left by a sweep that was killed
                    continue
                raise SweepError(f"another sweep (process {pid} on {host or '?'}) is writing to {self.root}; "
                                 f"wait for it or stop it (delete {path} if it is gone)") from None
            os.write(fd, me.encode())
            os.close(fd)
            break
        try:
            yield
        finally:
            path.unlink(missing_ok=True)

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
            writer = csv.writer(fh)
            writer.writerow(["case", "seed", *SAMPLE_FIELDS])
            for s in result["samples"]:
                writer.writerow([case, result["seed"], *(_fmt(s[c]) for c in SAMPLE_FIELDS)])
        os.replace(tmp, csv_path)
        meta = {k: v for k, v in result.items() if k != "samples"}
        meta["case"] = case
        tmp = json_path.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(meta, separators=(",", ":")))
        os.replace(tmp, json_path)  # last: marks the trial done

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


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError):
        return True
    return pid > 0


def _fmt(value: Any) -> Any:
    return repr(value) if isinstance(value, float) else value


def read_samples(path: Path) -> dict[str, np.ndarray]:
    with path.open(newline="") as fh:
        rows = list(csv.DictReader(fh))
    if not rows:
        raise ValueError("no samples")
    out: dict[str, np.ndarray] = {}
    for c in SAMPLE_FIELDS:
        values = [r[c] for r in rows]
        out[c] = np.array(values) if c == "phase" else np.array(values, dtype=float)
    out["step"] = out["step"].astype(int)
    return out


# ---------------------------------------------------------------------------
# Executors.


def _worker_init() -> None:
    # Ctrl-C is for the parent: it stops the workers itself (otherwise a worker
    # catches KeyboardInterrupt as a trial failure and goes on with the queue).
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def local_executor(workers: int) -> Iterator[cf.Executor]:
    # spawn: fresh interpreters, no inherited threads or pymunk state, same on every OS.
    ex = cf.ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"),
                                initializer=_worker_init)
    try:
        yield ex
    except BaseException:
        # Interrupted (or a bug): stop the trials in flight now, not after they finish.
        if hasattr(ex, "terminate_workers"):  # Python 3.14+
            ex.terminate_workers()
        else:
            for process in list(getattr(ex, "_processes", {}).values()):
                process.terminate()
        raise
    finally:
        ex.shutdown(wait=False, cancel_futures=True)


@contextlib.contextmanager
def dask_executor(address: str) -> Iterator[cf.Executor]:
    """Dask's own concurrent.futures executor on the cluster at ``address``."""
    try:
        from distributed import Client
    except ImportError:
        raise SweepError("--scheduler needs Dask; install it with: pip install 'phototaxis-sandbox[cluster]'") from None
    try:
        client = Client(address, timeout=DASK_CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SweepError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    try:
        # pure=False: a retried trial must run again, not return the cached failure.
        yield client.get_executor(pure=False)
    finally:
        client.close()


# ---------------------------------------------------------------------------
# The loop.


@dataclass
class Outcome:
    total: int
    skipped: int = 0
    done: int = 0
    failures: list[dict] = field(default_factory=list)
    seconds: float = 0.0


def run_trials(trials: list[Trial], store: ResultStore, executor: Callable[[], contextlib.AbstractContextManager],
               *, progress: bool = True, log: Callable[[str], None] | None = None) -> Outcome:
    """Run the trials not yet stored, saving each as it finishes.

    A trial that raises is retried once; if it fails again it is reported
    and the sweep goes on. A local worker process that dies takes its pool
    with it: the pool is restarted and the trials it held are retried.
    """
    from tqdm import tqdm

    todo = [t for t in trials if not store.is_done(t)]
    outcome = Outcome(total=len(trials), skipped=len(trials) - len(todo))
    bar = tqdm(total=len(trials), initial=outcome.skipped, unit="trial", disable=not progress,
               dynamic_ncols=True, file=sys.stderr, smoothing=0.1)
    say = log or (lambda msg: bar.write(msg, file=sys.stderr))
    start = time.perf_counter()
    attempts: dict[Trial, int] = {}
    try:
        with executor() as ex_holder:
            pool = [ex_holder]
            running: dict[cf.Future, Trial] = {}

            def submit(t: Trial) -> None:
                attempts[t] = attempts.get(t, 0) + 1
                running[pool[0].submit(run_trial, t.config, t.seed, t.config["steps"], t.shape)] = t

            for t in todo:
                submit(t)
            extra = contextlib.ExitStack()  # pools started after a worker process died
            while running:
                finished, _ = cf.wait(list(running), return_when=cf.FIRST_COMPLETED)
                again: list[Trial] = []
                broken = False
                for fut in finished:
                    t = running.pop(fut)
                    try:
                        result = fut.result()
                    except Exception as exc:  # noqa: BLE001 - a trial must never kill the sweep
                        broken |= type(exc).__name__ == "BrokenProcessPool"
                        message = (f"{type(exc).__name__}: {exc}".strip().splitlines() or ["error"])[0][:300]
                        if attempts[t] < ATTEMPTS:
                            say(f"trial {t.name} failed ({message}); retrying")
                            again.append(t)
                        else:
                            say(f"trial {t.name} failed again ({message}); giving up on it")
                            outcome.failures.append(dict(case=t.case, seed=t.seed, error=message,
                                                         traceback="".join(traceback.format_exception(exc))[-4000:]))
                            bar.update(1)
                        continue
                    try:
                        store.save(t.case, result)
                    except OSError as exc:
                        raise SweepError(f"cannot save trial {t.name} under {store.root}: "
                                         f"{exc.strerror or exc}") from None
                    outcome.done += 1
                    bar.update(1)
                if broken:
                    # Every other future of a dead pool fails too: take them all to a new pool.
                    for t in running.values():
                        if attempts[t] < ATTEMPTS:
                            again.append(t)
                        else:
                            say(f"trial {t.name} lost with a dead worker process; giving up on it")
                            outcome.failures.append(dict(case=t.case, seed=t.seed, error="worker process died",
                                                         traceback=""))
                            bar.update(1)
                    running.clear()
                    pool[0] = extra.enter_context(executor())
                for t in again:
                    submit(t)
            extra.close()
    finally:
        bar.close()
        outcome.seconds = time.perf_counter() - start
    return outcome

