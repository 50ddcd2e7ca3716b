"""``phototaxis run``: one headless trial, with a progress bar, a JSON summary,
an optional CSV trace of both success metrics and an optional design file (the
run's goal, settings, seed and light program); or the replay of a design file."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import IO, Any

from tqdm import tqdm

from sandbox.cli import (UserError, add_config_arguments, add_controller_argument, add_design_argument,
                         config_from_args, controller_from_args, design_from_args, program_time_limit)
from sandbox.model.config import CASES, STRATEGY_NAMES, Config
from sandbox.model import design as designs
from sandbox.model import watchdog
from sandbox.model.metrics import Sample, SampleWriter
from sandbox.model.programs import ProgramError, paper_controller_name
from sandbox.model.simulation import Simulation


def add_parser(sub: Any) -> argparse.ArgumentParser:

    p = sub.add_parser("run", help="run one headless trial and report both success metrics",
                       description="Run one headless trial. Every model parameter is a flag; "
                       "--case picks one of the paper's seven cases and explicit flags override it.")
    p.add_argument("--trace", metavar="FILE.csv", help="write both metrics every metrics_every steps to this CSV file")
    p.add_argument("--json", action="store_true", help="print one JSON object with the results on stdout")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.add_argument("--save-design", metavar="FILE.npz", default=None,
                   help="save the goal, the settings, the seed and the light program that ran in one file "
                        "(docs/design-files.md)")
    add_design_argument(p, "replay a design file: its goal, settings and seed under its recorded light program, "
                           "without the controller that first lit it (same result, bit for bit)")
    add_controller_argument(p)
    add_config_arguments(p)
    p.set_defaults(func=run_command)
    return p


def case_name(config: Config, given: str | None) -> str:
    """The case the configuration is, if it matches one exactly, else 'custom'."""
    strategies = {name: getattr(config, name) for name in STRATEGY_NAMES}
    for name, overrides in CASES.items():
        expected = dict.fromkeys(STRATEGY_NAMES, 0.0)
        expected.update((k, v) for k, v in overrides.items() if k != "shape")
        if overrides["shape"] == config.shape and strategies == expected:
            return name
    return f"{given}+custom" if given else "custom"


def open_trace(path: str | None) -> tuple[IO[str] | None, Any]:
    if not path:
        return None, None

    try:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        handle = open(path, "w", newline="", encoding="utf-8")
    except OSError as exc:
        raise UserError(f"cannot write trace file {path}: {exc.strerror or exc}") from None
    return handle, SampleWriter(handle)


def check_design_target(path: str | None, config: Config) -> None:
    """Refuse, before the run, a --save-design file that could not be written after it, or a design
    that could not be read back (a goal's name too long to show)."""
    if not path:
        return
    try:
        designs.check_recordable(config)
    except designs.DesignError as exc:
        raise UserError(f"--save-design {path}: {exc}") from None
    target = Path(path)
    if target.is_dir():
        raise UserError(f"--save-design {path}: that is a directory")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(f"--save-design {path}: cannot make its folder: {exc.strerror or exc}") from None
    if not os.access(target.parent, os.W_OK) or (target.exists() and not os.access(target, os.W_OK)):
        raise UserError(f"--save-design {path}: not writable")


def run_trial(config: Config, *, progress: bool = False, on_sample=None, program: Any = None,
              program_time_limit: float = watchdog.DEFAULT_LIMIT, shape: Any = "from-config",
              recorder: designs.PatternRecorder | None = None) -> tuple[Simulation, Sample, float]:
    """Run ``config.steps`` steps in chunks of ``metrics_every``; returns the
    simulation, its final sample and the wall time in seconds. ``shape``: the goal's
    vertices instead of ``config.shape``'s; ``recorder`` keeps the light program that runs."""
    sim = Simulation(config, program=program, program_time_limit=program_time_limit, shape=shape)
    if recorder is not None:
        recorder.attach(sim)
    if on_sample:
        on_sample(sim.history[0])
    chunk = config.metrics_every
    bar = tqdm(total=config.steps, unit="step", file=sys.stderr, disable=not progress, dynamic_ncols=True,
               desc=config.shape)
    started = time.perf_counter()
    try:
        while sim.steps_done < config.steps:
            n = min(chunk - sim.steps_done % chunk, config.steps - sim.steps_done)
            recorded = len(sim.history)
            sim.step(n)
            bar.update(n)
            if on_sample:
                for sample in sim.history[recorded:]:
                    on_sample(sample)
            if progress:
                bar.set_postfix(in_goal=f"{sim.history[-1].fraction_in_goal:.3f}", refresh=False)
    finally:
        bar.close()
    wall = time.perf_counter() - started
    final = sim.history[-1] if sim.history[-1].step == sim.steps_done else sim.measure()
    if final is not sim.history[-1] and on_sample:
        on_sample(final)
    return sim, final, wall


def cycles_of(sim: Simulation, design: designs.Design | None) -> int | None:
    """The contract-hold-dilate cycles the run went through, None where nothing here counted them. The
    simulation's count is the paper's controller's, which neither a replay nor a light program of the
    user's advances: a replay has the count its design recorded (None in a design made under a light
    program, or older than the count)."""
    if design is not None:
        return design.cycles
    return None if sim.user_program is not None else sim.cycle


def cycles_said(cycles: int | None, design: designs.Design | None) -> str:
    """The cycles for the summary line, or why they are not known and what is instead."""
    if cycles is not None:
        return f"{cycles} cycles" + (" (as recorded in the design)" if design is not None else "")
    if design is not None:
        return f"{len(design.steps)} light patterns (the design records no cycle count)"
    return "cycles not counted (a light program of your own)"


def run_command(args: argparse.Namespace) -> int:

    watchdog.on_stuck = watchdog.exit_on_stuck("phototaxis run")
    design = design_from_args(args)
    if design is not None:  # its own goal, settings and seed, lit by its recorded patterns
        config = design.config.replace(steps=design.steps_run)  # as long as it ran (a page's run is open-ended)
        shape, spec, program = design.shape, f"design {args.design}", designs.Replay(design)
        time_limit = 0.0  # the replay is ours, and asked every step: no watchdog around it
    else:
        config, shape = config_from_args(args), "from-config"
        (spec, program), time_limit = controller_from_args(args), program_time_limit(args)
    check_design_target(args.save_design, config)
    recorder = designs.PatternRecorder() if args.save_design else None
    handle, writer = open_trace(args.trace)
    try:
        def write(sample: Sample) -> None:
            if writer:
                writer.write(sample)
                handle.flush()

        sim, final, wall = run_trial(config, progress=not args.no_progress, on_sample=write, program=program,
                                     program_time_limit=time_limit, shape=shape, recorder=recorder)
        if recorder is not None:
            designs.save(recorder.design(sim, spec or paper_controller_name(config)), args.save_design)
    except (ProgramError, designs.DesignError) as exc:
        raise UserError(str(exc)) from None
    finally:
        if handle:
            handle.close()
    cycles = cycles_of(sim, design)
    result = {
        "case": case_name(config, args.case),
        "seed": config.seed,
        "steps": sim.steps_done,
        "robots": config.robots,
        "boxes": config.boxes,
        "fraction_in_goal": final.fraction_in_goal,
        "mean_outside_distance": final.mean_outside_distance,
        "boxes_escaped": final.boxes_escaped,
        "cycles": cycles,
        "outline": sim.goal.family,
        "outline_reason": sim.goal.family_reason,
        "goal_simplified": sim.goal.simplified,
        "controller": spec or paper_controller_name(config),
        "senses": sorted(sim.senses),
        "light_energy": round(sim.light_energy, 3),
        "wall_seconds": round(wall, 3),
        "steps_per_second": round(sim.steps_done / wall, 1) if wall > 0 else None,
        "config": config.to_dict(),
    }
    if design is not None:
        result["replayed_exactly"] = sim.state_digest() == design.result.get("state_digest")
    if args.save_design:
        result["design"] = args.save_design
    if args.json:
        json.dump(result, sys.stdout)
        sys.stdout.write("\n")
    else:
        print(f"case {result['case']}, seed {config.seed}: {sim.steps_done} steps, {cycles_said(cycles, design)}, "
              f"{wall:.1f} s ({result['steps_per_second']} steps/s)")
        print(f"  boxes in goal:             {final.fraction_in_goal:.3f}")
        print(f"  mean distance of the rest: {final.mean_outside_distance:.3f} m")
        print(f"  boxes escaped:             {final.boxes_escaped}")
        print(f"  outline:                   {sim.goal.family} ({sim.goal.family_reason})")
        if sim.goal.simplified:
            print(f"  goal:                      {sim.goal.simplified}")
        if design is not None:
            said = "yes" if result["replayed_exactly"] else "NO: the final state differs from the recorded one"
            print(f"  replayed exactly:          {said}")
        if args.save_design:
            print(f"  design saved to:           {args.save_design}")
    return 0
