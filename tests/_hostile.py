"""Shared harness of the hostile matrices (``tests/test_hostile_*.py``).

A hostile case is a realistic mistake of a user. Each case asserts three things:

1. the exact outcome: an exception class from the Python API, or an exit code from the
   command line (0 ok, 2 bad input, 3 failed solve, 130 interrupted; never 1, never a
   raw traceback);
2. the culprit named in the message (a column, row, item, spec line, path or option)
   and the fix;
3. that every input and every earlier output is byte-identical (and keeps its mode)
   afterwards: :func:`snapshot` before, :func:`assert_unchanged` after.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import stat
import subprocess
import sys
import warnings
from pathlib import Path

import pytest

#: Exit codes of the ``bvpnav`` command.
EXIT_OK, EXIT_INPUT, EXIT_SOLVE, EXIT_INTERRUPT = 0, 2, 3, 130


def snapshot(*roots: str | os.PathLike) -> dict[Path, tuple[bytes, int]]:
    """Bytes and permission bits of every regular file under ``roots`` (files or folders)."""
    out: dict[Path, tuple[bytes, int]] = {}
    for root in map(Path, roots):
        paths = [root] if root.is_file() else sorted(p for p in root.rglob("*") if p.is_file())
        for p in paths:
            out[p.resolve()] = (p.read_bytes(), stat.S_IMODE(p.stat().st_mode))
    return out


def assert_unchanged(before: dict[Path, tuple[bytes, int]]) -> None:
    """Every file of a :func:`snapshot` still exists with the same bytes and mode."""
    for p, (data, mode) in before.items():
        assert p.exists(), f"{p} was deleted"
        assert p.read_bytes() == data, f"{p} was modified"
        assert stat.S_IMODE(p.stat().st_mode) == mode, f"{p} changed mode"


def stray_temporaries(*folders: str | os.PathLike) -> list[str]:
    """Temporary files of the atomic writer (``.<name>.<random>.tmp``) left in folders."""
    return sorted(p.name for d in map(Path, folders) if Path(d).is_dir()
                  for p in Path(d).rglob(".*.tmp"))


def run_cli(args: list[str], cwd: str | os.PathLike | None = None, timeout: float = 300,
            **kw) -> subprocess.CompletedProcess:
    """Run ``python -m bvpnav.cli ARGS`` in a subprocess (text output, no stdin)."""
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONWARNINGS="default")
    env.update(kw.pop("env", {}))
    return subprocess.run([sys.executable, "-m", "bvpnav.cli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout, env=env,
                          stdin=subprocess.DEVNULL, **kw)


def main_cli(args: list, cwd: str | os.PathLike | None = None) -> subprocess.CompletedProcess:
    """Run ``bvpnav.cli.main(ARGS)`` in this process, as :func:`run_cli` runs the command:
    its exit code (argparse's usage errors included), stdout and stderr as text, stdin empty,
    Python's default warning filters (``PYTHONWARNINGS=default``), in the folder ``cwd``.

    For tests of what the command does and says, where a process adds nothing but its start-up
    (about a second of imports); the entry point itself, signals, stdin, hangs and memory caps
    are tested through :func:`run_cli`. ``main`` restores the logging and warning state it
    changes (``bvpnav.log.configured``).
    """
    from bvpnav.cli import main

    out, err = io.StringIO(), io.StringIO()
    here = os.getcwd()
    stdin = sys.stdin
    with open(os.devnull) as devnull, contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), \
            warnings.catch_warnings():
        warnings.simplefilter("default")
        sys.stdin = devnull
        try:
            if cwd is not None:
                os.chdir(cwd)
            code = main([str(a) for a in args])
        except SystemExit as exc:  # argparse: --help, usage errors
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
            if not isinstance(exc.code, (int, type(None))):
                print(exc.code, file=sys.stderr)
        finally:
            os.chdir(here)
            sys.stdin = stdin
    return subprocess.CompletedProcess(["bvpnav", *map(str, args)], code, out.getvalue(), err.getvalue())


def assert_clean_failure(proc: subprocess.CompletedProcess, code: int, *patterns: str) -> None:
    """The command exited with ``code``, printed no traceback, and its stderr matches every
    regular expression in ``patterns`` (case-insensitive)."""
    err = proc.stderr
    assert proc.returncode == code, f"exit {proc.returncode}, expected {code}\n{err}"
    assert "Traceback" not in err, err
    for pat in patterns:
        assert re.search(pat, err, re.IGNORECASE | re.DOTALL), f"{pat!r} not in:\n{err}"


def raises_named(exc_type, fn, *patterns: str):
    """``fn()`` raises exactly ``exc_type`` (or a subclass) whose message matches every
    pattern (case-insensitive); returns the exception."""
    with pytest.raises(exc_type) as info:
        fn()
    msg = str(info.value)
    for pat in patterns:
        assert re.search(pat, msg, re.IGNORECASE | re.DOTALL), f"{pat!r} not in: {msg}"
    return info.value
