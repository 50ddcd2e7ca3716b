"""``phototaxis bench``: how fast the engine runs and where the time goes.

Runs the paper's configuration (or any other: every parameter is a flag)
and reports steps per second, the share of wall time inside pymunk's
``Space.step`` against our own code, and peak memory. ``--scale K``
multiplies both populations by K in an arena K^(1/2) times wider (density
kept); ``--live`` measures the browser app with a real client connected; ``--hosted K`` K worlds in
world hosts, headless (:mod:`.hosted_bench`).
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import sys
import time
from pathlib import Path
from typing import Any

from tqdm import tqdm

from sandbox.commands import live_bench
from sandbox.app.world.lockstep import COMPARE_CASES
from sandbox.cli import UserError, add_config_arguments, config_from_args
from sandbox.model.config import Config
from sandbox.model.simulation import Simulation


def add_parser(sub: Any) -> argparse.ArgumentParser:

    p = sub.add_parser("bench", help="measure steps per second and where the time goes",
                       description="Benchmark the engine on the paper's configuration (circle, 200 robots, "
                       "500 boxes) unless flags say otherwise.")
    p.add_argument("--scale", type=float, default=1.0, metavar="K",
                   help="K times the robots and boxes in an arena sqrt(K) times wider (default 1)")
    p.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    p.add_argument("--live", action="store_true",
                   help="measure the browser sandbox with a headless Chromium client connected instead")
    p.add_argument("--seconds", type=float, default=20.0, help="how long --live measures (default 20)")
    p.add_argument("--steps-per-frame", type=int, default=25, metavar="N",
                   help="with --live: the app's speed setting, 1-100 (default 25, the app's default; 100: as "
                        "fast as it can)")
    p.add_argument("--viewers", type=int, default=1, metavar="K",
                   help="with --live: K viewers besides the browser (websocket clients that receive the scene "
                   "like a browser but draw nothing; they count the bytes); 9 makes a class of 10 (default 1)")
    p.add_argument("--no-browser", action="store_true",
                   help="with --live: no browser, only the websocket viewers (what the app costs without the "
                   "browser's drawing, which shares this machine's cores)")
    p.add_argument("--compare-with", metavar="CASE", default=None,
                   help="with --live: in compare mode against this case (a paper case, or 'star + chase'), "
                        "both worlds measured")
    p.add_argument("--hosted", type=int, default=None, metavar="K",
                   help="K worlds in world hosts (a class's worlds, headless, no web server) at 3x real time on "
                        "hosts up to the core count, for --seconds: steps and frames per second of each world, "
                        "CPU and memory of each host")
    p.add_argument("--class", dest="class_students", type=int, default=None, metavar="K",
                   help="a class server (serve --class) with K students' pages over websockets (they receive "
                        "frames as a page that keeps up does), for --seconds after a warm-up: each student "
                        "world's real-time factor and frames a second to its page, bytes a second per student, "
                        "the wall's refresh, the server's CPU and memory")
    p.add_argument("--class-challenge", type=int, default=None, metavar="STEPS",
                   help="with --class: then a class challenge of STEPS steps for every student, measured to the "
                        "end of its reference runs (the paper's controller in each round's world): peak memory "
                        "and processes")
    p.add_argument("--teacher-browser", action="store_true",
                   help="with --class: the teacher's page (the wall) in a headless Chromium too")
    p.add_argument("--hosts", type=int, default=None, metavar="N",
                   help="with --hosted: at most N host processes (default: the number of cores)")
    p.add_argument("--skip", type=int, default=0, metavar="STEPS",
                   help="with --hosted or --class: first run world i of K to step STEPS x i / K (spread over a "
                        "run and its denser phases, as a class's worlds are when students start at different "
                        "times), through the hosts' queues of builds")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.add_argument("--compare-reference", metavar="PATH",
                   help="also time a locally built binary of the authors' program (github AdamBignell/push) on "
                   "the paper's circle trial, 100,000 steps, as whole processes, in turn with ours; prints the ratio")
    p.add_argument("--rounds", type=int, default=1, help="with --compare-reference: alternate this many times "
                   "and report medians (default 1)")
    p.add_argument("--advice", action="store_true",
                   help="time the default advice (phototaxis advise) on every shape in shapes/, the circle and the "
                        "drawing templates, and check each first choice against the best at 100,000 steps in the "
                        "committed evaluations (static/shapes; from the repository's root): a table, or --json; "
                        "exit 1 if one is more than a point below the best. About 10 CPU-minutes")
    p.add_argument("--generated", type=int, default=None, metavar="N",
                   help="with --advice: the advice on the N shapes of a draw of the shape generator instead "
                        "(--families, --generator-seed as in sweep), judged against --truth; prints the share of "
                        "shapes whose first choice is within a point of the best and the wrong ones; exit 1 below "
                        "90 %%. --steps sets the advice's trials' steps (default its own, 10,000)")
    p.add_argument("--families", default="all", metavar="all|FAMILY,...",
                   help="with --advice --generated: the families of the draw [default: all]")
    p.add_argument("--generator-seed", type=int, default=0, metavar="S",
                   help="with --advice --generated: the draw [default: 0]")
    p.add_argument("--part", default=None, metavar="K/N",
                   help="with --advice --generated: only the K-th of N runs of consecutive shapes of the draw, "
                        "as sweep --part (a draw's truth made in parts, on several machines or days)")
    p.add_argument("--truth", action="append", default=None, metavar="DIR",
                   help="with --advice --generated: the report folder of the draw's candidates sweep (sweep "
                        "--generated N --candidates, then report), or a final.csv; repeatable")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="with --advice --generated: keep each shape's advice in DIR as it ends; the same command "
                        "again resumes where it stopped, or judges the kept advice on a truth that has grown")
    p.add_argument("--truth-steps", type=int, default=100_000, metavar="K",
                   help="with --advice --generated: the truth's trials are read at K steps [default: 100000]")
    add_config_arguments(p)
    p.set_defaults(func=bench_command)
    return p


#: The paper's circle case as the authors' program takes it (its README's flags; -x, headless, must come last).
REFERENCE_ARGS = ["-r", "200", "-b", "500", "-z", "0.5", "-s", "0.5", "-t", "C", "-y", "H", "-g", "50",
                  "-d", "0", "-c", "0", "-x"]
REFERENCE_STEPS = 100_000  # fixed in the program
#: How the two sides of --compare-reference are seeded: the released program takes no seed.
SEEDING = ("ours: seed {seed}; the authors' program: its clock (the released program reads no seed), so the two "
           "runs time the same case, not the same world")


def time_process(command: list[str], cwd: str) -> dict[str, Any]:
    """Wall time, CPU time and peak memory of one whole process. The peak RSS
    comes from GNU time where it is installed: a child's own ru_maxrss also
    counts the pages of this (large) process it was forked from."""
    import os
    import shutil
    import subprocess

    gnu_time = shutil.which("time") if os.path.isfile("/usr/bin/time") else None
    report = os.path.join(cwd, "rss.txt")
    wrapped = [gnu_time, "-f", "%M", "-o", report, *command] if gnu_time else command
    with open(os.path.join(cwd, "out.txt"), "w+") as out:
        started = time.perf_counter()
        process = subprocess.Popen(wrapped, cwd=cwd, stdout=out, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.perf_counter() - started
        process.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        lines = out.read().strip().splitlines()
    if process.returncode != 0:
        raise RuntimeError(f"{os.path.basename(command[0])} exited with code {process.returncode}: "
                           f"{lines[-1] if lines else 'no output'}")
    try:
        with open(report) as fh:
            peak_kb = float(fh.read().strip().splitlines()[-1])
    except (OSError, ValueError, IndexError):
        peak_kb = float("nan")
    return {"wall_seconds": round(wall, 2), "cpu_seconds": round(usage.ru_utime + usage.ru_stime, 2),
            "peak_rss_mb": round(peak_kb / 1024.0, 1), "last_line": lines[-1] if lines else ""}


def compare_reference(binary: str, rounds: int, config: Config) -> dict[str, Any]:
    """Time the authors' program and ours on the same 100,000-step circle trial, in turn."""
    import os
    import statistics
    import tempfile


    path = os.path.abspath(os.path.expanduser(binary))
    if not (os.path.isfile(path) and os.access(path, os.X_OK)):
        raise UserError(f"--compare-reference: {binary} is not an executable file (build the authors' program first)")
    if rounds < 1:
        raise UserError(f"--rounds must be at least 1, got {rounds}")
    ours_cmd = [sys.executable, "-m", "sandbox", "run", "--case", "circle", "--steps", str(REFERENCE_STEPS),
                "--seed", str(config.seed), "--no-progress", "--profile", config.profile]
    runs: dict[str, list[dict[str, Any]]] = {"reference": [], "ours": []}
    with tempfile.TemporaryDirectory() as scratch:  # the program may write files where it runs
        for _ in range(rounds):
            for name, command in (("reference", [path, *REFERENCE_ARGS]), ("ours", ours_cmd)):
                try:
                    runs[name].append(time_process(command, scratch))
                except (OSError, RuntimeError) as exc:
                    raise UserError(f"--compare-reference: {exc}") from None
    result: dict[str, Any] = {"steps": REFERENCE_STEPS, "rounds": rounds, "seeding": SEEDING.format(seed=config.seed)}
    for name, measured in runs.items():
        wall = statistics.median(m["wall_seconds"] for m in measured)
        result[name] = {"wall_seconds": wall, "steps_per_second": round(REFERENCE_STEPS / wall, 1),
                        "cpu_seconds": statistics.median(m["cpu_seconds"] for m in measured),
                        "peak_rss_mb": max(m["peak_rss_mb"] for m in measured),
                        "every_wall_seconds": [m["wall_seconds"] for m in measured],
                        "last_line": measured[-1]["last_line"]}
    result["speedup"] = round(result["reference"]["wall_seconds"] / result["ours"]["wall_seconds"], 2)
    return result


def scaled(config: Config, k: float) -> Config:
    """The same densities and light pitch in a bigger (k > 1) world."""
    if k == 1.0:
        return config
    grow = math.sqrt(k)
    pitch = config.light_pitch

    def whole_pitches(x: float) -> float:
        return max(pitch, round(x * grow / pitch) * pitch)

    return config.replace(
        arena_size=whole_pitches(config.arena_size),
        construction_size=whole_pitches(config.construction_size),
        robot_spawn_size=whole_pitches(config.robot_spawn_size),
        robots=int(round(config.robots * k)),
        boxes=int(round(config.boxes * k)),
    )


def peak_rss_mb() -> float:
    # ru_maxrss is in KiB on Linux.
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def measure(config: Config, steps: int, progress: bool = False) -> dict[str, Any]:
    """Run ``steps`` steps and time them; the world's construction is not counted."""
    sim = Simulation(config)
    chunk = max(1, min(1000, steps))
    bar = tqdm(total=steps, unit="step", file=sys.stderr, disable=not progress, dynamic_ncols=True)
    started = time.perf_counter()
    cpu_started = time.process_time()
    rss_samples = []
    while sim.steps_done < steps:
        n = min(chunk, steps - sim.steps_done)
        sim.step(n)
        bar.update(n)
        rss_samples.append(peak_rss_mb())
    wall = time.perf_counter() - started
    cpu = time.process_time() - cpu_started
    bar.close()
    t = sim.timings
    final = sim.measure()
    ours = wall - t["physics"]
    return {
        "steps": steps,
        "robots": config.robots,
        "boxes": config.boxes,
        "arena_size": config.arena_size,
        "wall_seconds": round(wall, 3),
        "steps_per_second": round(steps / wall, 1),
        # On a shared machine CPU time is steadier than wall time.
        "cpu_seconds": round(cpu, 3),
        "steps_per_cpu_second": round(steps / cpu, 1) if cpu > 0 else None,
        "physics_share": round(t["physics"] / wall, 3),
        "lights_share": round(t["lights"] / wall, 3),
        "metrics_share": round(t["metrics"] / wall, 3),
        "robots_share": round((ours - t["lights"] - t["metrics"]) / wall, 3),
        "us_per_step": {"physics": round(t["physics"] / steps * 1e6, 1), "ours": round(ours / steps * 1e6, 1)},
        "full_trial_seconds": round(100_000 * wall / steps, 1),
        "peak_rss_mb": round(peak_rss_mb(), 1),
        "rss_growth_mb_second_half": round(rss_samples[-1] - rss_samples[len(rss_samples) // 2], 1),
        "field_updates": sim.lights.rebuilds,
        "nan": sim.has_nan(),
        "boxes_escaped": final.boxes_escaped,
        "fraction_in_goal": round(final.fraction_in_goal, 4),
        "cycles": sim.cycle,
    }


def bench_command(args: argparse.Namespace) -> int:

    if not (args.scale > 0 and math.isfinite(args.scale)):
        raise UserError(f"--scale must be a positive number, got {args.scale}")
    if args.out is not None and (not args.advice or args.generated is None):
        raise UserError("--out keeps the advice on a draw: bench --advice --generated N --truth DIR --out DIR")
    if args.part is not None and (not args.advice or args.generated is None):
        raise UserError("--part splits a draw: bench --advice --generated N --part K/N --truth DIR")
    if args.advice:
        return advice_bench(args) if args.generated is None else draw_advice_bench(args)
    if args.generated is not None:
        raise UserError("--generated goes with --advice: bench --advice --generated N --truth DIR")
    if args.skip < 0:
        raise UserError(f"--skip takes the steps to spread the worlds over, 0 or more, got {args.skip}")
    if args.skip and args.hosted is None and args.class_students is None:
        raise UserError("--skip spreads a class's worlds: it goes with --hosted K or --class K")
    if args.steps is None:
        args.steps = 20_000  # a benchmark default: two full cycles, not a whole trial
    config = scaled(config_from_args(args), args.scale)
    if args.compare_reference:
        result = compare_reference(args.compare_reference, args.rounds, config)
    elif args.class_students is not None:
        from sandbox.commands import class_bench

        if not 1 <= args.class_students <= 40:
            raise UserError(f"--class takes 1 to 40 students (the class's seats), got {args.class_students}")
        if not 1 <= args.steps_per_frame <= 100:
            raise UserError(f"--steps-per-frame must be between 1 and 100, got {args.steps_per_frame}")
        result = class_bench.run(config, args.class_students, args.seconds, teacher_browser=args.teacher_browser,
                                 steps_per_frame=args.steps_per_frame, challenge_steps=args.class_challenge,
                                 spread=args.skip)
    elif args.hosted is not None:
        from sandbox.commands import hosted_bench

        result = hosted_bench.run(config, args.hosted, args.seconds, hosts=args.hosts, skip=args.skip)
    elif args.live:
        if not args.seconds > 0:
            raise UserError(f"--seconds must be positive, got {args.seconds}")
        if not 1 <= args.steps_per_frame <= 100:
            raise UserError(f"--steps-per-frame must be between 1 and 100, got {args.steps_per_frame}")
        if not 0 <= args.viewers <= 100:
            raise UserError(f"--viewers must be between 0 and 100, got {args.viewers}")
        if args.compare_with is not None and args.compare_with not in COMPARE_CASES:
            raise UserError(f"--compare-with takes a case: {', '.join(COMPARE_CASES)}")
        result = live_bench.run(config, args.seconds, steps_per_frame=args.steps_per_frame, viewers=args.viewers,
                                compare_with=args.compare_with, browser=not args.no_browser)
    else:
        if config.steps <= 0:
            raise UserError("--steps must be at least 1 for a benchmark")
        result = measure(config, config.steps, progress=not args.no_progress)
    if args.json:
        json.dump(result, sys.stdout)
        sys.stdout.write("\n")
    else:
        width = max(len(k) for k in result)
        for key, value in result.items():
            print(f"{key:<{width}}  {value}")
    return 0


def advice_bench(args: argparse.Namespace) -> int:
    """``bench --advice``: the default advice on every shape checked, timed and checked
    (:mod:`sandbox.experiments.advice_check`)."""
    from sandbox.commands.generated import ADVICE_EVALUATIONS, ADVICE_SHAPES
    from sandbox.experiments import advice_check
    from sandbox.experiments.advise import default_workers

    config, workers = config_from_args(args), default_workers()
    truth = advice_check.read_evaluations(ADVICE_EVALUATIONS)
    runs = []
    for shape in advice_check.shapes_checked(ADVICE_SHAPES):
        if not args.no_progress:
            print(f"bench --advice: {shape}", file=sys.stderr, flush=True)
        runs.append(advice_check.timed_advice(shape, config, workers=workers))
    verdicts = [advice_check.judge(run.shape, run.ranking, truth) for run in runs]
    if args.json:
        json.dump([{"shape": v.shape, "verdict": run.verdict, "first_at_100k": v.at_100k, "best": v.best,
                    "best_at_100k": v.best_at_100k, "status": v.status, "seconds": round(run.seconds, 1),
                    "cpu_seconds": round(run.cpu_seconds, 1), "estimates": run.estimates}
                   for v, run in zip(verdicts, runs)], sys.stdout)
        sys.stdout.write("\n")
    else:
        print(advice_check.table(runs, truth, workers))
    return 1 if any(v.status == "wrong" for v in verdicts) else 0


def draw_advice_bench(args: argparse.Namespace) -> int:
    """``bench --advice --generated N``: the advice on a draw of generated shapes, each first choice judged
    against the draw's candidates sweep (``--truth``): the share right, the wrong ones
    (:class:`sandbox.experiments.advice_check.DrawCheck`); exit 1 below the share wanted."""
    from sandbox.experiments import advice_check
    from sandbox.experiments.advise import STEPS, default_workers
    from sandbox.experiments.draws import Draw
    from sandbox.experiments.trials import SweepError
    from sandbox.shapes import ShapeError

    if not args.truth:
        raise UserError("bench --advice --generated needs --truth DIR: the report of the draw's candidates sweep "
                        "(phototaxis sweep --generated N --candidates --steps 100000, then phototaxis report)")
    try:
        wanted = Draw.from_flags(args.generated, args.families, args.generator_seed, args.part)
        shapes = wanted.shapes()
        truth = advice_check.read_evaluations(advice_check.truth_files(args.truth), args.truth_steps)
    except (SweepError, ShapeError, ValueError) as exc:
        raise UserError(str(exc)) from None
    config, workers = config_from_args(args), default_workers()
    steps = config.steps if args.steps is not None else STEPS
    try:
        runs, refused = advice_check.advise_draw(
            config, shapes, workers=workers, steps=steps, store=Path(args.out) if args.out else None,
            heard=None if args.no_progress else lambda name: print(f"bench --advice: {name}", file=sys.stderr,
                                                                    flush=True))
    except (ValueError, OSError) as exc:
        raise UserError(str(exc)) from None
    check = advice_check.DrawCheck([advice_check.judge(r.shape, r.ranking, truth, every_one=True) for r in runs],
                                   refused)
    if args.json:
        json.dump({"share_right": check.share_right, "passes": check.passes, "refused": refused,
                   "shapes": [{"shape": v.shape, "verdict": run.verdict, "first": v.first,
                               "first_at_truth": v.at_100k, "best": v.best, "best_at_truth": v.best_at_100k,
                               "status": v.status, "unmeasured": list(v.unmeasured),
                               "cpu_seconds": round(run.cpu_seconds, 1)}
                              for v, run in zip(check.verdicts, runs)]}, sys.stdout)
        sys.stdout.write("\n")
    else:
        print(advice_check.table(runs, truth, workers, steps, args.truth_steps))
        print()
        print("\n".join(check.summary(args.truth_steps)))
    return 0 if check.passes else 1
