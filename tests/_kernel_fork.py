"""Notebook kernels forked from a warm process, for the documentation build of the test suite.

The site build (conftest's ``docs_build``) executes 15 pages, each in a kernel of its own. A
fresh kernel pays the interpreter start and the imports of IPython, ipykernel, numpy, scipy,
cvxpy, pandas, matplotlib and bvpnav before its first cell, the same work 15 times. Here a
server process imports them once (:data:`PRELOAD`: imports only, no code of a page); each kernel
is a ``fork`` of it that then starts ipykernel as ``python -m ipykernel_launcher -f FILE``
would, in the launcher's folder, with the launcher's environment and standard streams. Every
cell of every page still runs in a process of its own and the build still fails on an error.

:func:`start_server` writes a ``python3`` kernel spec whose command is this file's ``launch``
(the build finds it first on ``JUPYTER_PATH``) and starts the server as a child of the caller
(its CPU time and its kernels' are the caller's children's). The server waits for the first
kernel and then becomes, by ``exec``, a process with that kernel's environment before it makes
the imports. A launcher (the small process the notebook client starts and signals as it would
a kernel) hands its arguments, folder, environment and standard streams over a Unix socket to
the server, forwards the signals it gets to the forked kernel and exits with its status; a
forked kernel whose launcher is killed ends too. A kernel whose environment differs from the
first one's (other than in :data:`PER_KERNEL`), or any launcher without a server, gets a fresh
``python -m ipykernel_launcher`` instead.
"""

from __future__ import annotations

import json
import os
import signal
import socket
import struct
import subprocess
import sys
from pathlib import Path

#: What the server imports once for all the kernels: what every kernel imports as it starts
#: and what most pages import. Not the inline backend: it hooks into the running IPython when
#: it is imported.
PRELOAD = (
    # the kernel's own
    "ipykernel.kernelapp", "ipykernel.ipkernel", "ipykernel.zmqshell", "ipykernel.debugger",
    "IPython.core.completerlib", "IPython.core.debugger", "IPython.core.oinspect", "IPython.core.pylabtools",
    "IPython.extensions.storemagic", "psutil", "sqlite3", "tornado.platform.asyncio",
    # the pages'
    "numpy", "scipy.linalg", "scipy.sparse", "scipy.sparse.linalg", "scipy.interpolate",
    "scipy.spatial.transform", "pandas", "cvxpy", "matplotlib", "matplotlib.pyplot",
    "matplotlib.backends.backend_agg", "bvpnav", "bvpnav.problem", "bvpnav.constraints",
    "bvpnav.error_models", "bvpnav.scenarios", "bvpnav.plot", "bvpnav.log", "bvpnav.solve.pipeline",
    "bvpnav.solve.uncertainty", "bvpnav.lam.lcurve", "bvpnav.lam.gcv", "bvpnav.lam.quasi",
    "bvpnav.lam.discrepancy", "bvpnav.lam.sweep", "bvpnav.linalg.banded", "bvpnav.linalg.lsq",
    "bvpnav.linalg.covariance", "bvpnav.linalg.selinv", "bvpnav.linalg.ipm", "bvpnav.linalg.active_set",
    "bvpnav.linalg.condensed", "bvpnav.backends.direct", "bvpnav.backends.cvxpy_solvers",
)
#: Variables set per kernel, which no import reads; every other variable must equal the server's.
PER_KERNEL = ("JPY_PARENT_PID", "JPY_SESSION_NAME", "PWD", "OLDPWD")
SOCKET_VAR = "BVPNAV_KERNEL_FORK_SOCKET"
#: Seconds between the server's checks that the process that started it is still there.
ORPHAN_CHECK = 5.0
FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT, signal.SIGUSR1, signal.SIGUSR2)
_LEN = struct.Struct("!I")


def start_server(folder: Path) -> tuple[subprocess.Popen, dict[str, str]]:
    """Start the server for one build: write the ``python3`` kernel spec into ``folder``,
    start the server (a child of the caller, which stops it with :func:`stop_server`) and
    return it with the environment variables under which a notebook client starts its
    kernels through this module (``JUPYTER_PATH`` and the server's socket)."""
    spec = folder / "kernels" / "python3"
    spec.mkdir(parents=True, exist_ok=True)
    (spec / "kernel.json").write_text(json.dumps({
        "argv": [sys.executable, str(Path(__file__).resolve()), "launch", "-f", "{connection_file}"],
        "display_name": "Python 3", "language": "python", "interrupt_mode": "signal",
    }))
    path = folder / "server.sock"
    listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    listener.bind(str(path))
    listener.listen(16)
    with open(folder / "server.log", "w") as log:
        command = [sys.executable, str(Path(__file__).resolve()), "serve", str(listener.fileno()),
                   str(os.getpid())]
        proc = subprocess.Popen(command, pass_fds=[listener.fileno()], stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=log)
    listener.close()
    return proc, {"JUPYTER_PATH": str(folder), SOCKET_VAR: str(path)}


def stop_server(proc: subprocess.Popen, folder: Path) -> int:
    """Stop the server; return how many kernels it forked."""
    proc.terminate()
    proc.wait(timeout=60)
    count = folder / "server.forks"
    return int(count.read_text()) if count.exists() else 0


def _fresh_kernel(args: list[str]) -> None:
    os.execv(sys.executable, [sys.executable, "-m", "ipykernel_launcher", *args])


def _recv_exact(conn: socket.socket, n: int) -> bytes:
    data = b""
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            raise ConnectionError("closed")
        data += chunk
    return data


def _connect(path: str) -> socket.socket | None:
    """A connection to the build's server, or None (no server: a fresh kernel)."""
    conn = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        conn.connect(path)
        return conn
    except OSError:
        conn.close()
        return None


def launch(args: list[str]) -> None:
    """The kernel command: a kernel forked by the server, or a fresh one."""
    path = os.environ.get(SOCKET_VAR)
    conn = _connect(path) if path else None
    if conn is None:
        _fresh_kernel(args)
    msg = json.dumps({"args": args, "cwd": os.getcwd(), "env": dict(os.environ)}).encode()
    try:
        socket.send_fds(conn, [_LEN.pack(len(msg)) + msg], [0, 1, 2])
        pid = struct.unpack("!i", _recv_exact(conn, 4))[0]
    except OSError:  # the server stopped meanwhile (ConnectionError is one)
        pid = 0
    if pid <= 0:
        conn.close()
        _fresh_kernel(args)

    def forward(signum, frame):
        try:
            os.kill(pid, signum)
        except ProcessLookupError:
            pass

    for sig in FORWARDED:
        signal.signal(sig, forward)
    while True:
        try:
            status = struct.unpack("!i", _recv_exact(conn, 4))[0]
            break
        except InterruptedError:
            continue
        except ConnectionError:
            status = 1
            break
    sys.exit(status)


class _Child(Exception):
    """Raised in a forked kernel to leave the server's loop and start ipykernel."""

    def __init__(self, request: dict, conn: socket.socket):
        super().__init__()
        self.request, self.conn = request, conn


def _exit_status(status: int) -> int:
    return os.waitstatus_to_exitcode(status) if hasattr(os, "waitstatus_to_exitcode") else status >> 8


def _request(conn: socket.socket) -> tuple[dict, list[int]]:
    msg, fds, _, _ = socket.recv_fds(conn, 1 << 20, 3)
    length = _LEN.unpack(msg[:4])[0]
    data = msg[4:]
    while len(data) < length:
        data += _recv_exact(conn, length - len(data))
    return json.loads(data), fds


def serve(listener_fd: int, parent: int) -> None:
    """The server as started: wait for the first kernel, then become the warm server in its
    environment (the interpreter's start and the imports read the variables the kernels get)."""
    import select

    listener = socket.socket(fileno=listener_fd)
    signal.signal(signal.SIGTERM, lambda *a: sys.exit(0))
    while not select.select([listener], [], [], ORPHAN_CHECK)[0]:
        if os.getppid() != parent:
            return  # the build's process is gone
    conn, _ = listener.accept()
    request, fds = _request(conn)
    first = Path(listener.getsockname()).parent / "first.json"
    first.write_text(json.dumps(request))
    for fd in (listener.fileno(), conn.fileno(), *fds):
        os.set_inheritable(fd, True)
    os.execve(sys.executable, [sys.executable, str(Path(__file__).resolve()), "warm", str(parent),
                               str(listener.fileno()), str(conn.fileno()), *map(str, fds), str(first)],
              request["env"])


class _Server:
    """The warm server's state: its listening socket, the running kernels, the forks made."""

    def __init__(self, listener: socket.socket, env0: dict[str, str]):
        import selectors

        self.listener = listener
        self.folder = Path(listener.getsockname()).parent
        self.env0 = env0
        self.sel = selectors.DefaultSelector()
        self.sel.register(listener, selectors.EVENT_READ, None)
        self.running: dict[int, tuple[int, socket.socket]] = {}  # pidfd -> (pid, launcher connection)
        self.pending: list[tuple[socket.socket, dict, list[int]]] = []
        self.forks = 0

    def start(self, conn: socket.socket, request: dict, streams: list[int]) -> None:
        """Fork a kernel for one launcher (or tell it to start a fresh one)."""
        import selectors

        same = {k: v for k, v in request["env"].items() if k not in PER_KERNEL} == self.env0
        if not same or len(streams) != 3:
            print(f"fresh kernel: {sorted(set(request['env'].items()) ^ set(self.env0.items()))}",
                  file=sys.stderr, flush=True)
            for fd in streams:
                os.close(fd)
            conn.sendall(struct.pack("!i", 0))
            conn.close()
            return
        pid = os.fork()
        if pid == 0:
            self.close_in_child(conn)
            for target, fd in enumerate(streams):
                os.dup2(fd, target)
                os.close(fd)
            raise _Child(request, conn)
        for fd in streams:
            os.close(fd)
        self.forks += 1
        (self.folder / "server.forks").write_text(str(self.forks))
        pidfd = os.pidfd_open(pid)
        self.running[pidfd] = (pid, conn)
        self.sel.register(pidfd, selectors.EVENT_READ, (pid, conn))
        conn.sendall(struct.pack("!i", pid))

    def close_in_child(self, conn: socket.socket) -> None:
        """A forked kernel keeps its own launcher's connection and nothing else of the server."""
        self.sel.close()
        self.listener.close()
        for pidfd, (_, other) in self.running.items():
            os.close(pidfd)
            other.close()
        for other, _, streams in self.pending:
            if other is not conn:
                other.close()
                for fd in streams:
                    os.close(fd)

    def ended(self, pidfd: int, pid: int, conn: socket.socket) -> None:
        """A kernel ended: its status to its launcher."""
        self.sel.unregister(pidfd)
        os.close(pidfd)
        self.running.pop(pidfd, None)
        _, status, usage = os.wait4(pid, 0)
        print(f"kernel {pid}: status {status}, CPU user {usage.ru_utime:.2f} s sys {usage.ru_stime:.2f} s",
              file=sys.stderr, flush=True)
        try:
            conn.sendall(struct.pack("!i", _exit_status(status)))
        except OSError:
            pass
        conn.close()

    def run(self, parent: int) -> None:
        while True:
            while self.pending:
                self.start(*self.pending.pop(0))
            events = self.sel.select(timeout=ORPHAN_CHECK)
            if not events and os.getppid() != parent:
                return
            for key, _ in events:
                if key.data is None:  # a launcher
                    conn, _ = self.listener.accept()
                    self.pending.append((conn, *_request(conn)))
                else:
                    self.ended(key.fd, *key.data)


def warm(parent: int, listener_fd: int, conn_fd: int, fds: list[int], first: Path) -> None:
    """Import :data:`PRELOAD`, then fork one kernel per launcher that connects (the first
    one already connected: ``conn_fd`` with its streams ``fds`` and its request in ``first``)."""
    import gc
    import importlib

    signal.signal(signal.SIGTERM, lambda *a: sys.exit(0))
    env0 = {k: v for k, v in os.environ.items() if k not in PER_KERNEL}  # before the imports change it
    for name in PRELOAD:
        try:
            importlib.import_module(name)
        except ImportError as exc:  # a module renamed: the kernels import it themselves
            print(f"preload: {name}: {exc}", file=sys.stderr, flush=True)
    gc.freeze()  # what the imports made stays out of the kernels' collections (they keep it all)
    server = _Server(socket.socket(fileno=listener_fd), env0)
    server.pending.append((socket.socket(fileno=conn_fd), json.loads(first.read_text()), fds))
    server.run(parent)


def _kernel(child: _Child) -> None:
    """In the forked process: become ``python -m ipykernel_launcher ARGS`` in the launcher's
    folder and environment (its streams are already 0, 1, 2)."""
    import threading

    request, conn = child.request, child.conn
    for sig in (signal.SIGTERM, *FORWARDED):
        signal.signal(sig, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    os.chdir(request["cwd"])
    # the launcher's environment: the server's (what the imports set included) but the per-kernel ones
    for name in PER_KERNEL:
        if name in request["env"]:
            os.environ[name] = request["env"][name]
        else:
            os.environ.pop(name, None)
    sys.argv = [str(Path(__import__("ipykernel_launcher").__file__)), *request["args"]]
    if "numpy.random" in sys.modules:
        sys.modules["numpy.random"].seed()  # the global generator from fresh entropy, as at start

    def orphan_guard():
        """If the launcher dies (killed), the kernel goes too."""
        while True:
            try:
                if not conn.recv(1):
                    break
            except InterruptedError:
                continue
            except OSError:
                break
        os.kill(os.getpid(), signal.SIGKILL)

    threading.Thread(target=orphan_guard, daemon=True).start()
    from ipykernel import kernelapp

    kernelapp.launch_new_instance()


def main() -> None:
    here = str(Path(__file__).resolve().parent)
    if sys.path and sys.path[0] == here:
        del sys.path[0]  # as ipykernel_launcher drops its own folder
    command, args = sys.argv[1], sys.argv[2:]
    if command == "launch":
        launch(args)
    elif command == "serve":
        serve(int(args[0]), int(args[1]))
    elif command == "warm":
        try:
            warm(int(args[0]), int(args[1]), int(args[2]), [int(a) for a in args[3:-1]], Path(args[-1]))
        except _Child as child:
            _kernel(child)


if __name__ == "__main__":
    main()
