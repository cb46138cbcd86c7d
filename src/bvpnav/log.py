"""Logging, progress bars and warnings of bvpnav.

Logging
    Every module logs to ``logging.getLogger(__name__)``, children of the ``"bvpnav"``
    logger, which has only a :class:`logging.NullHandler`: nothing is printed unless the
    application configures logging (``logging.basicConfig(level=logging.INFO)``, or
    :func:`configure` as the CLI does). At INFO: each fallback attempt and its reason
    (``bvpnav.solve.chain``), the back end that answered with its timings, the lambda
    each rule chose with the sweep's engine, evaluations and seconds
    (``bvpnav.lam.sweep``), every sequential iteration with its largest change and mode
    (``bvpnav.solve.sequential``), demoted items (``bvpnav.solve.conflicts``) and each
    finished recording of a batch (``bvpnav.batch``). At DEBUG: the solver options in
    force and the verification measures. The solver's own output is not logged: it is
    ``solve(verbose=True)``, which cvxpy's back ends print to stdout.

Progress
    :func:`progress` wraps ``tqdm.auto``: the lambda sweep, the sequential loop and batch
    show a bar only when stderr is a terminal (never in pipes, files, CI or tests), after
    half a second, and not with ``progress=False`` or after ``configure(-1)`` (``-q``).

Warnings
    :func:`warn` issues a :class:`BvpnavWarning` (a ``RuntimeWarning``) through
    :mod:`warnings` with the stack level of the first frame outside bvpnav, so the
    reported line is the user's call, and only once per public call (:func:`once`): a
    lambda-rule warning raised on every iteration of a sequential loop, or also copied into
    ``solution.warnings``, is issued a single time.

Signals
    :func:`signal_handled` installs a signal handler for the duration of a block and
    restores the one before it (the CLI's SIGTERM, a batch's notes of SIGINT and SIGTERM,
    its workers started with Ctrl-C ignored); off the main thread it changes nothing.
"""

from __future__ import annotations

import contextlib
import contextvars
import logging
import os
import signal
import sys
import warnings
from collections.abc import Callable, Iterator

__all__ = ["BvpnavWarning", "DataWarning", "FrameWarning", "SaturationWarning",
           "configure", "configured", "warn", "once", "progress", "progress_enabled",
           "logger", "in_sweep", "sweeping", "issued", "signal_handled"]

logger = logging.getLogger("bvpnav")
logger.addHandler(logging.NullHandler())


class BvpnavWarning(RuntimeWarning):
    """A warning about a choice the user can change (the lambda range, the loop's tolerance)."""


class DataWarning(BvpnavWarning):
    """A warning about the input data themselves, issued when they are built
    (:class:`bvpnav.ImuData`, a reader) and copied into ``solution.warnings`` by the solve."""


class FrameWarning(DataWarning):
    """The navigation-frame acceleration at rest is not about zero: a frame, gravity or
    axis-convention mistake (:func:`bvpnav.detect.frame_check`)."""


class SaturationWarning(DataWarning):
    """Gyro samples at the sensor's range: clipped rates (:func:`bvpnav.detect.saturation`)."""


# ------------------------------------------------------------------------ warnings
_SEEN: contextvars.ContextVar[set | None] = contextvars.ContextVar("bvpnav_warned", default=None)
_HERE = os.path.dirname(os.path.abspath(__file__))


def _internal_dirs() -> tuple[str, ...]:
    dirs = [_HERE]
    mod = sys.modules.get("bvpnav.constraints")  # a package of its own folder (see pyproject)
    path = getattr(mod, "__file__", None)
    if path:
        dirs.append(os.path.dirname(os.path.abspath(path)))
    return tuple(d + os.sep for d in dirs)


def _stacklevel() -> int:
    """The ``stacklevel`` for a ``warnings.warn`` call made in :func:`warn`: the first frame
    outside bvpnav (and ``bvpnav.constraints``)."""
    prefixes = _internal_dirs()
    frame = sys._getframe(2)  # the caller of warn()
    level = 2
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(prefixes):
        frame = frame.f_back
        level += 1
    return level


def warn(message: str, category: type[Warning] = BvpnavWarning) -> bool:
    """Issue ``message`` once per public call, attributed to the user's line.

    Returns False (and issues nothing) when the same message was already issued within the
    current :func:`once` scope.
    """
    seen = _SEEN.get()
    if seen is not None:
        if (category, message) in seen:
            return False
        seen.add((category, message))
    warnings.warn(message, category, stacklevel=_stacklevel())
    return True


@contextlib.contextmanager
def once():
    """A scope in which each warning message is issued once (nested scopes share the outer's).

    Public entry points (``solve``, ``lambda_curve``, ``sweep_curve``, batch) open one.
    """
    if _SEEN.get() is not None:
        yield
        return
    token = _SEEN.set(set())
    try:
        yield
    finally:
        _SEEN.reset(token)


def issued(message: str, category: type[Warning] = BvpnavWarning) -> bool:
    """Whether ``message`` was already issued in the current :func:`once` scope."""
    seen = _SEEN.get()
    return seen is not None and (category, message) in seen


# --------------------------------------------------------------------- sweep context
_SWEEP: contextvars.ContextVar[bool] = contextvars.ContextVar("bvpnav_sweeping", default=False)


@contextlib.contextmanager
def sweeping():
    """Marks the fixed-lambda solves of a lambda sweep (their per-solve records go to DEBUG)."""
    token = _SWEEP.set(True)
    try:
        yield
    finally:
        _SWEEP.reset(token)


def in_sweep() -> bool:
    """True inside :func:`sweeping`."""
    return _SWEEP.get()


# ------------------------------------------------------------------------ progress
_PROGRESS_OFF = False


def progress_enabled(progress: bool | None = None) -> bool:
    """Whether to show a bar: ``progress=True`` always, ``False`` never, ``None`` (the
    default) when stderr is a terminal and the CLI was not given ``-q``."""
    if progress is not None:
        return bool(progress)
    if _PROGRESS_OFF:
        return False
    try:
        return bool(sys.stderr is not None and sys.stderr.isatty())
    except (AttributeError, ValueError):  # a replaced or closed stderr
        return False


def progress(iterable=None, *, total=None, desc: str = "", unit: str = "it", enabled: bool | None = None,
             **kw):
    """A ``tqdm.auto`` bar (shown after 0.5 s, removed when done), disabled unless
    :func:`progress_enabled`; disabled, an object with the same calls that does nothing
    (tqdm is not imported: ``tqdm.auto`` loads asyncio, a tenth of a second per process)."""
    if not progress_enabled(enabled):
        return _NoBar(iterable)
    from tqdm.auto import tqdm

    kw.setdefault("leave", False)
    kw.setdefault("delay", 0.5)
    return tqdm(iterable, total=total, desc=desc, unit=unit, file=sys.stderr, **kw)


class _NoBar:
    """A disabled progress bar: iterates ``iterable`` and ignores every bar call."""

    def __init__(self, iterable=None):
        self.iterable = iterable
        self.n = 0

    def __iter__(self):
        return iter(self.iterable if self.iterable is not None else ())

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> bool:
        return False

    def update(self, n: float = 1) -> None:
        self.n += n

    def __getattr__(self, name: str):   # set_postfix_str, set_description, close, refresh, ...
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *args, **kwargs: None


# ----------------------------------------------------------------------- configure
_HANDLER_TAG = "_bvpnav_cli_handler"


def configure(verbosity: int = 0, *, quiet_warnings: bool = True) -> logging.Handler:
    """Set up bvpnav's logging for a command-line run (the ``bvpnav`` command calls it).

    Parameters
    ----------
    verbosity : int
        ``-1`` (``-q``): errors only, no progress bars; ``0``: warnings; ``1`` (``-v``):
        INFO (fallbacks, chosen lambda, iterations, timings); ``2`` or more (``-vv``):
        DEBUG (solver options, verification measures).
    quiet_warnings : bool
        Do not let Python display :class:`BvpnavWarning` (default True): the CLI prints
        ``solution.warnings`` / ``curve.warnings``, which hold every one of them, as
        ``warning: ...`` lines (``-q`` hides those too), so they would otherwise show twice,
        the second time quoting a source line.

    Returns
    -------
    logging.Handler
        The stderr handler installed on the ``bvpnav`` logger (replacing one from an
        earlier call).
    """
    global _PROGRESS_OFF
    verbosity = int(verbosity)
    level = (logging.ERROR if verbosity < 0 else logging.WARNING if verbosity == 0
             else logging.INFO if verbosity == 1 else logging.DEBUG)
    for h in list(logger.handlers):
        if getattr(h, _HANDLER_TAG, False):
            logger.removeHandler(h)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("bvpnav: %(levelname)s: %(message)s" if verbosity < 2
                                           else "bvpnav: %(levelname)s %(name)s: %(message)s"))
    setattr(handler, _HANDLER_TAG, True)
    logger.addHandler(handler)
    logger.setLevel(level)
    _PROGRESS_OFF = verbosity < 0
    if quiet_warnings:
        warnings.filterwarnings("ignore", category=BvpnavWarning)
    return handler


@contextlib.contextmanager
def configured(verbosity: int = 0, *, quiet_warnings: bool = True):
    """:func:`configure` for the duration of a block (one command-line run), then the
    ``bvpnav`` logger's handlers and level, the progress switch and the warning filters as
    they were: ``bvpnav.cli.main([...])`` called from Python leaves no global state behind.
    """
    global _PROGRESS_OFF
    handlers, level, progress_off = list(logger.handlers), logger.level, _PROGRESS_OFF
    with warnings.catch_warnings():
        configure(verbosity, quiet_warnings=quiet_warnings)
        try:
            yield
        finally:
            logger.handlers[:] = handlers
            logger.setLevel(level)
            _PROGRESS_OFF = progress_off


# ------------------------------------------------------------------------- signals
@contextlib.contextmanager
def signal_handled(signum: int, handler: Callable | int) -> Iterator[bool]:
    """Handle ``signum`` with ``handler`` (a function or :data:`signal.SIG_IGN`) inside the
    block, then restore the handler that was there before.

    Yields whether the handler was installed. The block runs either way: off the main
    thread signals are not ours to change (:func:`signal.signal` raises ValueError there),
    nor a signal the platform does not let a process handle (OSError). When the handler
    before was not installed from Python (:func:`signal.signal` returned None), there is
    nothing to restore it with and ``handler`` stays.
    """
    try:
        old = signal.signal(signum, handler)
    except (ValueError, OSError):
        installed = False
    else:
        installed = True
    if not installed:  # yielded outside the except clause: the block's errors are not chained to it
        yield False
        return
    try:
        yield True
    finally:
        if old is not None:
            signal.signal(signum, old)
