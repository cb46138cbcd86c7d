"""Peak resident memory of one benchmark case, measured in a child process.

``ru_maxrss`` of a process only ever grows, so measuring several cases in one process
reports the largest so far. Each case here runs in its own Python child, which reports
its own high-water mark ``VmHWM`` from ``/proc/self/status`` (Linux): unlike
``ru_maxrss``, that belongs to the child's fresh address space and does not inherit the
parent's peak across fork and exec.
"""

from __future__ import annotations

import json
import subprocess
import sys


def own_peak_mb() -> float:
    """This process's peak resident memory, MB (VmHWM; ru_maxrss where /proc is missing)."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def run_case(script: str, args: list[str]) -> dict:
    """Run ``python script --case args...`` and return its JSON line plus ``peak_mb``.

    The child prints one JSON object (its measurements, with ``peak_mb`` from
    :func:`own_peak_mb`) as its last line of output.
    """
    proc = subprocess.Popen([sys.executable, script, "--case", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    out, err = proc.communicate()
    lines = [ln for ln in out.splitlines() if ln.startswith("{")]
    res = json.loads(lines[-1]) if lines else {"error": (err.strip().splitlines() or ["no output"])[-1]}
    if proc.returncode != 0 and "error" not in res:
        res["error"] = f"exit code {proc.returncode}"
    res.setdefault("peak_mb", float("nan"))
    return res
