"""README.md stays true: every command it shows runs, and what it quotes is what it quotes.

Each shell command in README.md's ``bash`` / ``sh`` code blocks runs here, with a
short-run substitution where the real one takes long (``--steps 300``, one trial
per case); ``serve`` is started, asked for its page over HTTP and stopped. The
commands that set up a machine (venv, pip) are checked for syntax only, and the
test command is this suite itself. A README command of a kind not listed here
fails the test, so that each new one gets a decision, not silence.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import urllib.error
import urllib.request
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
TEST_COMMAND = "python -m pytest -q"
SHELL_BLOCKS = {"bash", "sh", "shell"}
#: Short versions of long commands: flags set (or replaced) before a command runs; None is a bare flag.
SHORT = {
    "run": {"--steps": "300", "--no-progress": None},
    "record": {"--steps": "300", "--no-progress": None},
    # Without figures: 3.5 s of matplotlib, drawn and checked in tests/experiments/test_experiment.py.
    "sweep": {"--trials": "1", "--steps": "300", "--workers": "1", "--no-progress": None, "--no-figures": None},
    "bench": {"--steps": "300", "--no-progress": None},
    "report": {},
}
SHORT_LIVE_BENCH = {"--seconds": "3", "--no-progress": None}
SERVE_START_SECONDS = 120  # a fresh simulation process compiles or loads numba's cache


# ------------------------------------------------------------------ parsing
@dataclass(frozen=True)
class Command:
    line: int  # README.md line the command starts on
    text: str  # as shown (continuation lines joined), its comment included

    def parts(self) -> list[list[str]]:
        """The command's ``&&``-separated parts, each as argv."""
        lexer = shlex.shlex(self.text, posix=True, punctuation_chars=True)
        lexer.whitespace_split = True
        lexer.commenters = "#"  # as in bash only at the start of a word: README commands have no '#' inside one
        parts, current = [], []
        for token in lexer:
            if token == "&&":
                parts.append(current)
                current = []
            elif token in (";", "|", "||", "&", ">", "<", ">>"):
                raise AssertionError(f"README.md:{self.line}: keep README commands to '&&' chains: {self.text}")
            else:
                current.append(token)
        parts.append(current)
        return parts


def shell_commands(text: str) -> list[Command]:
    """Every command of the shell code blocks (continuation lines joined); comment lines are not commands."""
    commands, block, pending, start = [], None, "", 0
    for number, line in enumerate(text.splitlines(), 1):
        fence = re.match(r"^\s*```(\S*)", line)
        if fence:
            block = None if block is not None else fence.group(1)
            continue
        if block not in SHELL_BLOCKS:
            continue
        if not pending:
            start = number
        pending += line
        if pending.endswith("\\"):
            pending = pending[:-1] + " "
            continue
        if shlex.split(pending, comments=True):
            commands.append(Command(start, pending.strip()))
        pending = ""
    return commands


def kind(argv: list[str]) -> str:
    """What a part of a command is: 'setup', 'tests', or the phototaxis subcommand it runs."""
    if argv[:3] in (["python3", "-m", "venv"], ["python", "-m", "venv"]) or argv[0] in (".", "source"):
        return "setup"
    if argv[0] == "pip" or argv[1:3] == ["-m", "pip"]:
        return "setup"
    if argv[:3] == ["python", "-m", "pytest"]:
        return "tests"
    sandbox = phototaxis_args(argv)
    if sandbox is None:
        return "unknown"
    if not sandbox or sandbox[0].startswith("-"):
        return "serve"  # as the dispatcher does
    return sandbox[0] if sandbox[0] == "serve" or sandbox[0] in SHORT else "unknown"


def phototaxis_args(argv: list[str]) -> list[str] | None:
    if argv[0] == "phototaxis":
        return argv[1:]
    if argv[:3] in (["python", "-m", "sandbox"], ["python3", "-m", "sandbox"]):
        return argv[3:]
    return None


def shortened(args: list[str]) -> list[str]:
    """``args`` with the short-run flags of its subcommand set."""
    args = list(args)
    if kind(["phototaxis", *args]) == "serve":
        return args  # started and stopped, however long it would run
    flags = SHORT_LIVE_BENCH if args[0] == "bench" and "--live" in args else SHORT[args[0]]
    for flag, value in flags.items():
        if flag in args:
            if value is not None:
                args[args.index(flag) + 1] = value
        else:
            args += [flag] if value is None else [flag, value]
    return args


COMMANDS = shell_commands(README.read_text(encoding="utf-8"))


def runnable(commands: list[Command]) -> list[tuple[Command, list[str]]]:
    """(command, argv) of every part that runs something, each distinct argv once, in README order."""
    seen, found = set(), []
    for command in commands:
        for argv in command.parts():
            if kind(argv) not in ("setup", "tests") and tuple(argv) not in seen:
                seen.add(tuple(argv))
                found.append((command, argv))
    return found


RUNNABLE = runnable(COMMANDS)


# ------------------------------------------------------------------- checks
def test_readme_shows_commands_of_known_kinds():
    assert COMMANDS, "no shell commands found in README.md"
    for command in COMMANDS:
        for argv in command.parts():
            assert kind(argv) != "unknown", (
                f"README.md:{command.line}: {command.text!r}: tests/test_readme.py does not know how to check this "
                f"command; teach it (kind, SHORT) or show it in docs/ instead")


def test_setup_commands_are_valid_shell():
    setups = [c for c in COMMANDS if any(kind(argv) == "setup" for argv in c.parts())]
    assert len(setups) >= 2  # the browser sandbox's and the tests'
    for command in setups:
        done = subprocess.run(["bash", "-n", "-c", command.text], capture_output=True, text=True)
        assert done.returncode == 0, f"README.md:{command.line}: {done.stderr}"


def test_readme_names_the_test_command_ci_runs():
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert TEST_COMMAND in ci
    tests = [argv for c in COMMANDS for argv in c.parts() if kind(argv) == "tests"]
    assert tests == [shlex.split(TEST_COMMAND)], "README.md must show the test command exactly once, as .ci/run runs it"


def test_readme_shows_the_example_light_program_as_it_is():
    example = (ROOT / "examples" / "shrinking_ring.py").read_text(encoding="utf-8")
    assert example in README.read_text(encoding="utf-8")
    assert len(example.strip().splitlines()) <= 25


def test_shortening_keeps_the_command_and_bounds_its_length():
    assert shortened(["run", "--case", "star", "--steps", "100000", "--json"]) == [
        "run", "--case", "star", "--steps", "300", "--json", "--no-progress"]
    assert shortened(["sweep", "--cases", "paper", "--trials", "10", "--out", "runs/paper"]) == [
        "sweep", "--cases", "paper", "--trials", "1", "--out", "runs/paper", "--steps", "300", "--workers", "1",
        "--no-progress", "--no-figures"]
    assert shortened(["report", "runs/paper"]) == ["report", "runs/paper"]


# ------------------------------------------------------------------ running
@pytest.fixture(scope="module")
def workdir(tmp_path_factory) -> Path:
    """Where README commands run: a fresh folder that sees the repository's examples/ and shapes/."""
    path = tmp_path_factory.mktemp("readme")
    for name in ("examples", "shapes"):
        (path / name).symlink_to(ROOT / name, target_is_directory=True)
    return path


def phototaxis(args: list[str], cwd: Path, monkeypatch) -> int:
    """Run a command as ``python -m sandbox`` does (in this process: the imports are paid once)."""
    from sandbox import commands

    monkeypatch.chdir(cwd)
    return commands.main(args)


def sweep_writing(folder: str) -> list[str] | None:
    """The README's sweep command that writes ``folder``, if any (a ``report`` reads it)."""
    for _, argv in RUNNABLE:
        args = phototaxis_args(argv)
        if args and args[0] == "sweep" and "--out" in args and args[args.index("--out") + 1] == folder:
            return args
    return None


HEADLESS = [(c, argv) for c, argv in RUNNABLE if kind(argv) != "serve"]
SERVED = [(c, argv) for c, argv in RUNNABLE if kind(argv) == "serve"]


@pytest.mark.slow
@pytest.mark.parametrize("command,argv", HEADLESS, ids=[" ".join(argv) for _, argv in HEADLESS])
def test_readme_command_runs(command, argv, workdir, monkeypatch):
    args = phototaxis_args(argv)
    if args[0] == "report":
        source = sweep_writing(args[1])
        assert source is not None, f"README.md:{command.line}: a report of a folder no README sweep writes"
        if not (workdir / args[1] / "sweep.json").exists():
            assert phototaxis(shortened(source), workdir, monkeypatch) == 0
    code = phototaxis(shortened(args), workdir, monkeypatch)
    assert code == 0, f"README.md:{command.line}: {command.text} exited with {code}"


def environment() -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), *filter(None, [env.get("PYTHONPATH")])])  # this checkout
    return env


class Server:
    """``python -m sandbox serve ...`` in a process (and process group) of its own."""

    def __init__(self, args: list[str], cwd: Path):
        # In a session of its own (so that stop() can end its group), it would outlive a test process
        # that is killed: one such server still ran 13 minutes later. setpriv (util-linux) has the
        # kernel send it SIGTERM when this process ends, as a service manager would.
        guard = ["setpriv", "--pdeathsig", "TERM", "--"] if shutil.which("setpriv") else []
        self.proc = subprocess.Popen([*guard, sys.executable, "-m", "sandbox", *args], cwd=cwd, env=environment(),
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                     start_new_session=True)
        self.output: list[str] = []
        self.asked = False
        self.address = threading.Event()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            self.output.append(line)
            if re.search(r"http://\S+:\d+/", line):
                self.address.set()

    def answers(self) -> int:
        """The HTTP status of its page, once it has printed its address."""
        self.address.wait(SERVE_START_SECONDS)  # returns as soon as the address is printed
        assert self.address.is_set(), f"serve printed no address: {''.join(self.output)}"
        port = re.search(r"http://\S+:(\d+)/", "".join(self.output)).group(1)
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=30) as response:
                return response.status
        except urllib.error.HTTPError as exc:  # an answer all the same (e.g. a page that asks to log in)
            return exc.code

    def ask_to_stop(self) -> None:
        """SIGTERM, once, as a service manager sends it."""
        if self.proc.poll() is None and not self.asked:
            self.proc.send_signal(signal.SIGTERM)
            self.asked = True

    def stop(self) -> int:
        """Stop it (SIGTERM) and return its exit code."""
        self.ask_to_stop()
        try:
            return self.proc.wait(60)
        finally:
            if self.proc.poll() is None:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)
            self.reader.join(10)


@pytest.mark.slow
def test_readme_serve_commands_answer_and_stop(workdir):
    """Every ``serve`` the README shows starts, answers HTTP and exits with 0 when stopped.
    They start together: each spends most of its start waiting for its simulation process. Each is
    asked to stop as soon as it has answered, so that it does not simulate beside the next ones."""
    assert SERVED, "README.md shows no serve command"
    servers = [(command, argv, Server(phototaxis_args(argv), workdir)) for command, argv in SERVED]
    failures = []
    try:
        for command, argv, server in servers:
            try:
                status = server.answers()
                if status >= 500:
                    failures.append(f"README.md:{command.line}: {command.text}: answered HTTP {status}")
            except AssertionError as exc:
                failures.append(f"README.md:{command.line}: {command.text}: {exc}")
            server.ask_to_stop()
    finally:
        for command, argv, server in servers:
            code = server.stop()
            if code != 0:
                failures.append(f"README.md:{command.line}: {command.text}: exited with {code}: "
                                f"{''.join(server.output)[-2000:]}")
    assert not failures, "\n".join(failures)
