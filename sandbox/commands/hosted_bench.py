"""``phototaxis bench --hosted K``: K worlds of the paper's size in world hosts (sandbox.app.world),
headless, each at a class's pace (3x real time): steps and frames per second of each world, CPU share
and memory of each host process, and the memory each world adds beyond the first.

No web server: the worlds' frames reach this process as they would reach the app's (each world's
:class:`~sandbox.app.world.hosted.HostedRunner` unpickles them and counts them); what the pages would
cost on top is issue 58's class benchmark. Memory is read from /proc (Linux): RSS, and PSS, which
shares out the pages the hosts share with the fork server they were forked from.
"""

from __future__ import annotations

import os
import statistics
import time
from typing import Any

from sandbox.app.world.hosted import CLASS_FPS, CLASS_STEPS_PER_FRAME, HostedRunner
from sandbox.app.world.orders import SkipAhead
from sandbox.app.world.pool import HostPool
from sandbox.cli import UserError
from sandbox.model.config import Config
from sandbox.processes import start_fork_server

#: Seconds the worlds run before the measurement starts (the first frames, the hosts' caches).
WARM_UP = 3.0
PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096
TICKS = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def cpu_seconds(pid: int) -> float:
    """User and system CPU seconds of process ``pid`` so far."""
    with open(f"/proc/{pid}/stat") as fh:
        fields = fh.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS


def memory_mb(pid: int) -> tuple[float, float]:
    """(RSS, PSS) of process ``pid`` in MB; PSS is RSS when the kernel does not say."""
    with open(f"/proc/{pid}/statm") as fh:
        rss = int(fh.read().split()[1]) * PAGE / 1e6
    try:
        with open(f"/proc/{pid}/smaps_rollup") as fh:
            pss = next(int(line.split()[1]) for line in fh if line.startswith("Pss:")) / 1e3
    except (OSError, StopIteration):
        pss = rss
    return rss, pss


def host_memory(pool: HostPool) -> tuple[float, float]:
    """Total (RSS, PSS) of the pool's live hosts, MB."""
    sizes = [memory_mb(host.process.pid) for host in pool.hosts if not host.dead]
    return sum(r for r, _ in sizes), sum(p for _, p in sizes)


def run(config: Config, worlds: int, seconds: float, hosts: int | None = None, skip: int = 0,
        fps: float = CLASS_FPS, steps_per_frame: int = CLASS_STEPS_PER_FRAME) -> dict[str, Any]:
    """Start ``worlds`` worlds on up to ``hosts`` hosts (the cores), each at ``fps`` x ``steps_per_frame``
    steps a second (world i of K first run to step ``skip`` x i / K, through the hosts' queues of builds:
    spread over the run, as a class's are), run them
    ``seconds`` seconds and report what each world and host did."""
    if worlds < 1 or seconds <= 0:
        raise UserError(f"--hosted needs at least one world and --seconds > 0 (got {worlds}, {seconds})")
    start_fork_server()
    pool = HostPool(hosts=hosts)
    runners: list[HostedRunner] = []
    try:
        runners.append(HostedRunner(config.replace(seed=config.seed), pool=pool, fps=fps,
                                    steps_per_frame=steps_per_frame).start())
        time.sleep(WARM_UP)  # one world running: the memory the first world costs
        first_rss, first_pss = host_memory(pool)
        for i in range(1, worlds):
            runners.append(HostedRunner(config.replace(seed=config.seed + i), pool=pool, fps=fps,
                                        steps_per_frame=steps_per_frame, wait=False))
        for runner in runners[1:]:
            runner.ready()
            runner.start()
        if skip > 0:  # spread over the first ``skip`` steps, as a class's worlds are over their runs
            futures = [runner.submit(SkipAhead(skip * i // worlds)) for i, runner in enumerate(runners, 1)]
            for future in futures:
                future.result(timeout=1800)
        time.sleep(WARM_UP)
        result = measure(pool, runners, seconds)
        rss, pss = host_memory(pool)
    finally:
        for runner in runners:
            runner.stop()
        pool.stop()
    beyond = max(worlds - 1, 1)
    result.update({
        "worlds": worlds, "hosts": len(result["per_host"]), "seconds": seconds, "target_steps_per_second":
        fps * steps_per_frame, "robots": config.robots, "boxes": config.boxes, "spread_over_steps": skip,
        "hosts_rss_mb": round(rss, 1), "hosts_pss_mb": round(pss, 1),
        "first_world_rss_mb": round(first_rss, 1), "first_world_pss_mb": round(first_pss, 1),
        "rss_per_world_beyond_first_mb": round((rss - first_rss) / beyond, 1) if worlds > 1 else None,
        "pss_per_world_beyond_first_mb": round((pss - first_pss) / beyond, 1) if worlds > 1 else None,
    })
    return result


def measure(pool: HostPool, runners: list[HostedRunner], seconds: float) -> dict[str, Any]:
    """Each world's steps and frames a second, each host's CPU share, over ``seconds``."""
    pids = sorted({host.process.pid for host in pool.hosts if not host.dead})
    steps = [runner.latest.step for runner in runners]
    frames = [runner.frames_published for runner in runners]
    cpu = {pid: cpu_seconds(pid) for pid in pids}
    app_cpu = time.process_time()
    started = time.perf_counter()
    time.sleep(seconds)  # the measurement window
    wall = time.perf_counter() - started
    step_rates = [(runner.latest.step - s) / wall for runner, s in zip(runners, steps)]
    frame_rates = [(runner.frames_published - f) / wall for runner, f in zip(runners, frames)]
    per_host, host_cpu = [], 0.0
    for pid in pids:
        host_cpu += cpu_seconds(pid) - cpu[pid]
        rss, pss = memory_mb(pid)
        per_host.append({"pid": pid, "worlds": sum(runner.process.pid == pid for runner in runners),
                         "cpu_share": round((cpu_seconds(pid) - cpu[pid]) / wall, 3),
                         "rss_mb": round(rss, 1), "pss_mb": round(pss, 1)})
    target = runners[0].fps * runners[0].steps_per_frame
    cpu_per_step = host_cpu / max(sum(step_rates) * wall, 1)  # the hosts' CPU a step costs, frames and all
    return {
        # what a loaded machine does not change much: the CPU a world's step costs in its host, and so how many
        # worlds one core holds at the target pace
        "host_cpu_us_per_step": round(cpu_per_step * 1e6, 1),
        "worlds_per_core_at_target": round(1 / (cpu_per_step * target), 1) if cpu_per_step > 0 else None,
        "steps_per_second": {"min": round(min(step_rates), 1), "median": round(statistics.median(step_rates), 1),
                             "max": round(max(step_rates), 1)},
        "frames_per_second": {"min": round(min(frame_rates), 1),
                              "median": round(statistics.median(frame_rates), 1)},
        "worlds_below_target": sum(rate < 0.95 * target for rate in step_rates),
        "per_host": per_host,
        "app_cpu_share": round((time.process_time() - app_cpu) / wall, 3),
        "load_average": round(os.getloadavg()[0], 1),  # what else the machine ran (the 1-minute load)
        "restarts": sum(runner.restarts for runner in runners),
    }
