"""Where trials run: local worker processes or a Dask cluster, and the loop
that feeds them, retries failures and stores each result as it arrives."""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import signal
import sys
import time
import traceback
from dataclasses import dataclass, field
from typing import Callable, Iterator

from sandbox.experiments.storage import ResultStore
from sandbox.experiments.trials import SweepError, Trial, run_sweep_trial
from sandbox.processes import simulation_context

ATTEMPTS = 2  # a failing trial is retried once
DASK_CONNECT_TIMEOUT = "15s"


def _worker_init() -> None:
    # Ctrl-C is for the parent: it stops the workers itself (otherwise a worker
    # catches KeyboardInterrupt as a trial failure and goes on with the queue).
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextlib.contextmanager
def local_executor(workers: int) -> Iterator[cf.Executor]:
    # No inherited threads or pymunk state: forks of the warmed-up fork server, else fresh interpreters.
    ex = cf.ProcessPoolExecutor(max_workers=workers, mp_context=simulation_context(),
                                initializer=_worker_init)
    try:
        yield ex
    except BaseException:
        # Interrupted (or a bug, or a SweepError): stop the trials in flight now, not after they finish.
        terminate_workers(ex)
        raise
    finally:
        ex.shutdown(wait=False, cancel_futures=True)


def terminate_workers(ex: cf.ProcessPoolExecutor) -> None:
    """End the pool's worker processes now, in the middle of their trials. Python 3.14 has a public
    way; before it, none: ``shutdown`` lets a running trial finish (minutes), so this reads the pool's
    private ``_processes`` (pid to Process), here only."""
    if hasattr(ex, "terminate_workers"):  # Python 3.14+
        ex.terminate_workers()
        return
    for process in list((getattr(ex, "_processes", None) or {}).values()):
        process.terminate()


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
        # Every pool it starts (another after a worker process died) is closed, its workers ended, however
        # the loop ends: a SweepError too.
        with contextlib.ExitStack() as pools:
            pool = [pools.enter_context(executor())]
            running: dict[cf.Future, Trial] = {}

            def submit(t: Trial) -> None:
                attempts[t] = attempts.get(t, 0) + 1
                running[pool[0].submit(run_sweep_trial, t.config, t.seed, t.config["steps"], t.shape,
                                           t.controller, t.program_time_limit)] = t

            for t in todo:
                submit(t)
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
                        if type(exc).__name__ == "ProgramError":  # the user's light program: retrying cannot help
                            raise SweepError(f"trial {t.name}: {exc}; the sweep stops (finished trials are "
                                             f"kept)") from None
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
                    pool[0] = pools.enter_context(executor())
                for t in again:
                    submit(t)
    finally:
        bar.close()
        outcome.seconds = time.perf_counter() - start
    return outcome

