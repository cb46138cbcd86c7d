"""Peak resident memory of one benchmark case, measured in a child process.

``ru_maxrss`` of a process only ever grows, so measuring several cases in one process
reports the largest so far. Each case here runs in its own Python child; ``os.wait4``
returns that child's own resource usage.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys


def run_case(script: str, args: list[str]) -> dict:
    """Run ``python script --case args...`` and return its JSON line plus ``peak_mb``.

    The child prints one JSON object (its measurements) as its last line of output.
    """
    proc = subprocess.Popen([sys.executable, script, "--case", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    out, err = proc.stdout.read(), proc.stderr.read()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    lines = [ln for ln in out.splitlines() if ln.startswith("{")]
    res = json.loads(lines[-1]) if lines else {"error": (err.strip().splitlines() or ["no output"])[-1]}
    if proc.returncode != 0 and "error" not in res:
        res["error"] = f"exit code {proc.returncode}"
    res["peak_mb"] = usage.ru_maxrss / 1024.0  # kB on Linux
    return res
