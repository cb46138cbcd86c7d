r"""Readers: how a file becomes samples (and information) for bvpnav.

Every reader is an object with the :class:`Reader` contract: a lowercase ``name``, the
file ``suffixes`` it claims, ``sniff(head)`` (does this file look like mine?), the
``options`` it takes from the spec's ``[input]``, the optional dependencies it needs
(``modules``, installed with ``pip install 'bvpnav[<extra>]'``), ``read(path, options)``
returning a :class:`Recording`, and ``example(folder)`` writing a tiny valid file (the
contract test reads it back: :func:`bvpnav.testing.check_reader`).

The family is a discovered folder, like ``bvpnav.constraints``: each module here defines
one reader and registers it with :func:`register_reader` on import. Adding a format is
one file.

A :class:`Recording` holds what the file says, in SI units and the sensor's own frame:
navigation-frame acceleration, or the strapdown channels (specific force, gyro rates,
an attitude) with their frames stated; information found in the file (GNSS fixes,
odometry) as items; and ``notes``: everything the reader did to the data (resampling a
sensor onto the accelerometer's times, aligning two clocks), said, never silent.
:meth:`Recording.imu_data` turns it into :class:`bvpnav.ImuData`.

Examples
--------
A CSV file read by its suffix (the table reader):

>>> import tempfile
>>> from pathlib import Path
>>> tmp = tempfile.TemporaryDirectory()
>>> path = Path(tmp.name) / "drive.csv"
>>> _ = path.write_text("t,acc_x\n0.0,0.5\n0.1,0.5\n0.2,0.5\n")
>>> from bvpnav.readers import read
>>> rec = read(path)
>>> rec.n, rec.axes, rec.acc[:, 0].tolist()
(3, ('x',), [0.5, 0.5, 0.5])
>>> rec.imu_data()
ImuData(N=3, axes=('x',), navigation-frame, t=[0, 0.2] s)
>>> tmp.cleanup()
"""

from __future__ import annotations

import difflib
import importlib
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import InputError
from ..plugins import discover

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np
    from scipy.spatial.transform import Rotation

    from ..imu import ImuData

__all__ = [
    "Recording",
    "Reader",
    "register_reader",
    "unregister_reader",
    "registry",
    "get_reader",
    "reader_for",
    "read",
    "require",
    "read_recording",
    "align",
]

#: Leading bytes a reader's ``sniff`` sees.
HEAD_BYTES = 4096


@dataclass(frozen=True, eq=False)
class Recording:
    """What one file holds, in SI units, before it becomes :class:`bvpnav.ImuData`.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Sample times in s from ``time_origin``, strictly increasing.
    source : str
        The file (and topic, sensor) the samples came from, for messages.
    time_origin : str or None
        What ``t = 0`` is: an absolute instant (``"2026-05-01T10:00:00.123456789Z"`` or
        ``"1700000000000000000 ns"`` since the Unix epoch) or None when the file's times
        are relative (then no other clock can be aligned to them without an offset).
    acc : ndarray, shape (N, d), optional
        Navigation-frame acceleration in m/s^2 (the table readers' classic form).
    axes : tuple of str, optional
        Axis names of ``acc``.
    specific_force : ndarray, shape (N, 3), optional
        What the accelerometer triad measured, m/s^2, sensor axes.
    gyro : ndarray, shape (N, 3), optional
        Angular rates, rad/s, sensor axes.
    attitude : scipy.spatial.transform.Rotation, optional
        Sensor-to-reference rotation per sample, as the file gives it.
    attitude_frame : str, optional
        The reference frame of ``attitude``: ``"enu"`` or ``"ned"`` (or a free text the
        reader states, e.g. ``"arbitrary heading, z up"``).
    items : tuple of Item
        Information found in the file (GNSS fixes as :class:`Position` items, odometry as
        :class:`Velocity` items), on the same clock as ``t``.
    notes : tuple of str
        What the reader did: every resampling, alignment or conversion, one sentence each.
    meta : dict
        Anything else worth keeping (topic names, device, geodetic origin).

    Notes
    -----
    A recording has ``acc`` (navigation frame already), or ``specific_force``, or neither
    (an *information-only* file such as a GNSS log: its ``items`` go beside another
    recording's samples through :func:`align`); with
    ``specific_force`` the attitude comes from ``attitude`` or from integrating ``gyro``
    (:meth:`bvpnav.ImuData.from_gyro`), and the navigation-frame acceleration is
    :math:`a = C_{nb} f + g`.

    Examples
    --------
    A recording made in code (a reader returns one); its samples become :class:`bvpnav.ImuData`:

    >>> import numpy as np
    >>> from bvpnav.readers import Recording
    >>> rec = Recording(t=np.array([0.0, 0.1, 0.2]), source="example", acc=np.full((3, 1), 0.5), axes=("x",))
    >>> rec.n, rec.is_strapdown
    (3, False)
    >>> rec.imu_data()
    ImuData(N=3, axes=('x',), navigation-frame, t=[0, 0.2] s)
    """

    t: np.ndarray
    source: str
    time_origin: str | None = None
    acc: np.ndarray | None = None
    axes: tuple[str, ...] | None = None
    specific_force: np.ndarray | None = None
    gyro: np.ndarray | None = None
    attitude: Rotation | None = None
    attitude_frame: str | None = None
    items: tuple = ()
    notes: tuple[str, ...] = ()
    meta: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of samples."""
        return int(len(self.t))

    @property
    def is_strapdown(self) -> bool:
        """True when the samples are body-frame specific force (and gyro/attitude)."""
        return self.specific_force is not None

    @property
    def is_information(self) -> bool:
        """True for an information-only recording (a GNSS log): no ``acc``, no
        ``specific_force``, only ``items`` on the clock of ``t``."""
        return self.acc is None and self.specific_force is None

    def items_in(self, frame: str) -> tuple:
        """The recording's items, checked to be in the navigation frame ``frame``.

        A reader that converts geodetic fixes states the local frame of its items in
        ``meta["frame"]``; items in another frame than the one solved in are refused (with
        the fix), never silently mixed.
        """
        own = self.meta.get("frame")
        if self.items and own is not None and own != frame:
            raise InputError(f"{self.source}: its {len(self.items)} item(s) (GNSS fixes, odometry) are in "
                             f"the local {own.upper()} frame but the spec's [input] frame is {frame!r}; set "
                             f"frame = \"{own}\" (or convert the items yourself)")
        return tuple(self.items)

    def imu_data(self, frame_options: Mapping[str, Any] | None = None) -> ImuData:
        """The samples as :class:`bvpnav.ImuData` (navigation-frame acceleration).

        Parameters
        ----------
        frame_options : mapping, optional
            The strapdown part of the spec's ``[input]`` (frame, gravity, body-to-sensor
            rotation, initial attitude); see :func:`bvpnav.strapdown.imu_data`.
        """
        from ..strapdown import imu_data

        return imu_data(self, dict(frame_options or {}))


class Reader:
    r"""The contract of a file format.

    Attributes
    ----------
    name : str
        Lowercase name, chosen in the spec with ``[input] format = "<name>"``.
    suffixes : tuple of str
        Lower-case file suffixes it claims (``".bag"``); a folder reader claims ``"/"``.
    options : frozenset of str
        The ``[input]`` keys it reads (besides ``format``); others are refused by name.
    modules : tuple of str
        Optional modules it imports (``"rosbags"``); :func:`require` names the extra.
    extra : str or None
        The ``pip install 'bvpnav[<extra>]'`` that brings ``modules``.
    description : str
        One line for ``bvpnav readers`` and the docs.

    Examples
    --------
    A reader for a made-up format of two columns, time (s) and acceleration (m/s^2):

    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from bvpnav.readers import Reader, Recording, read, register_reader, unregister_reader
    >>> class TwoColumns(Reader):
    ...     name = "twocol"
    ...     suffixes = (".twocol",)
    ...     description = "time (s) and acceleration (m/s^2), one sample a line"
    ...     def read(self, path, options):
    ...         t, a = np.loadtxt(path, unpack=True)
    ...         return Recording(t=t, source=str(path), acc=a[:, None], axes=("x",))
    >>> _ = register_reader(TwoColumns())
    >>> tmp = tempfile.TemporaryDirectory()
    >>> path = Path(tmp.name) / "walk.twocol"
    >>> _ = path.write_text("0.0 0.5\n0.1 0.5\n0.2 0.5\n")
    >>> read(path).imu_data()
    ImuData(N=3, axes=('x',), navigation-frame, t=[0, 0.2] s)
    >>> unregister_reader("twocol")
    >>> tmp.cleanup()
    """

    name: str = ""
    suffixes: tuple[str, ...] = ()
    options: frozenset = frozenset()
    modules: tuple[str, ...] = ()
    extra: str | None = None
    description: str = ""

    def sniff(self, head: bytes) -> bool:
        """Whether a file starting with ``head`` (up to 4 kB) is in this format."""
        return False

    def read(self, path: Path, options: Mapping[str, Any]) -> Recording:
        """Read ``path`` (never modified) with the checked ``[input]`` options."""
        raise NotImplementedError

    def example(self, folder: Path) -> Path:
        """Write a tiny valid file of this format into ``folder``; its path."""
        raise NotImplementedError

    def check_options(self, options: Mapping[str, Any], where: str) -> None:
        """Refuse ``[input]`` keys this reader does not take, naming the valid ones."""
        bad = sorted(set(options) - set(self.options) - {"format"})
        if bad:
            close = difflib.get_close_matches(bad[0], sorted(self.options), n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise InputError(f"{where}: [input] {bad[0]!r} is not an option of the {self.name!r} reader"
                             f"{hint}; its options: {sorted(self.options)}")

    def __repr__(self) -> str:
        return f"<reader {self.name!r} {list(self.suffixes)}>"


_READERS: dict[str, Reader] = {}


def register_reader(reader: Reader) -> Reader:
    """Register a reader under its name (replacing one of the same name); returns it.

    Examples
    --------
    >>> from bvpnav.readers import Reader, register_reader, registry, unregister_reader
    >>> class Mine(Reader):
    ...     name = "mine"
    ...     suffixes = (".mine",)
    >>> register_reader(Mine())
    <reader 'mine' ['.mine']>
    >>> "mine" in registry()
    True
    >>> unregister_reader("mine")
    """
    if not isinstance(reader, Reader) or not reader.name or reader.name != reader.name.lower():
        raise TypeError(f"{reader!r}: a reader is a Reader instance with a lowercase name")
    _READERS[reader.name] = reader
    return reader


def unregister_reader(name: str) -> None:
    """Remove a registered reader (tests).

    Examples
    --------
    >>> from bvpnav.readers import Reader, register_reader, registry, unregister_reader
    >>> class Mine(Reader):
    ...     name = "mine"
    >>> _ = register_reader(Mine())
    >>> unregister_reader("mine")
    >>> "mine" in registry()
    False
    """
    _READERS.pop(name, None)


def _discover() -> None:
    discover(__name__, __path__, first=("table",))


def registry() -> dict[str, Reader]:
    """Every reader by name.

    Examples
    --------
    >>> from bvpnav.readers import registry
    >>> sorted(registry())
    ['nmea', 'phone', 'rosbag', 'table']
    """
    _discover()
    return dict(_READERS)


def get_reader(name: str) -> Reader:
    """The reader called ``name``; an unknown name lists the known ones.

    Examples
    --------
    >>> import bvpnav
    >>> from bvpnav.readers import get_reader
    >>> get_reader("table")
    <reader 'table' ['.csv', '.parquet', '.pq']>
    >>> try:
    ...     get_reader("tabel")
    ... except bvpnav.InputError as exc:
    ...     print(exc)
    [input] format = 'tabel' is not a known reader (did you mean 'table'?); readers: [...]
    """
    table = registry()
    if not isinstance(name, str) or name.lower() not in table:
        close = difflib.get_close_matches(str(name), sorted(table), n=1)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise InputError(f"[input] format = {name!r} is not a known reader{hint}; readers: {sorted(table)}")
    return table[name.lower()]


def _head(path: Path) -> bytes:
    """The first bytes of a file; of a folder, the names of its files and of its subfolders'
    files (sorted, one per line), which is what a folder reader's ``sniff`` recognises."""
    if path.is_dir():
        try:
            names = sorted({p.name for p in path.rglob("*") if p.is_file()})
        except OSError:
            return b""
        return "\n".join(names[:200]).encode("utf-8", "replace")[:HEAD_BYTES]
    try:
        with open(path, "rb") as fh:
            return fh.read(HEAD_BYTES)
    except OSError:
        return b""


def reader_for(path: str | os.PathLike, format: str | None = None) -> Reader:
    """The reader for ``path``: the one named ``format``, else the one whose suffix and
    ``sniff`` agree, else the one whose suffix matches. A file no reader claims is refused
    with the list of formats.

    Examples
    --------
    >>> from bvpnav.readers import reader_for
    >>> reader_for("drive.csv").name, reader_for("gnss.nmea").name
    ('table', 'nmea')
    >>> reader_for("drive.txt", format="table").name
    'table'
    """
    if format is not None:
        return get_reader(format)
    p = Path(path)
    suffix = "/" if p.is_dir() else p.suffix.lower()
    table = registry()
    claim = [r for r in table.values() if suffix in r.suffixes]
    if len(claim) > 1:
        head = _head(p)
        sniffed = [r for r in claim if r.sniff(head)]
        claim = sniffed or claim[:1]
    if claim:
        return claim[0]
    known = sorted({s for r in table.values() for s in r.suffixes if s != "/"})
    raise InputError(f"{str(p)!r}: no reader for {suffix!r} files; known suffixes: {known} (or set "
                     f"[input] format = one of {sorted(table)})")


def require(reader: Reader, path: str | os.PathLike | None = None) -> None:
    """Import the reader's optional modules, or refuse naming the ``pip install``.

    Examples
    --------
    A reader's optional modules are imported, or the pip install is named:

    >>> from bvpnav.readers import get_reader, require
    >>> require(get_reader("table"))  # needs nothing beyond bvpnav's own dependencies
    >>> get_reader("rosbag").modules, get_reader("rosbag").extra
    (('rosbags', 'pymap3d'), 'ros')
    """
    for mod in reader.modules:
        try:
            importlib.import_module(mod)
        except ImportError:
            where = f"{str(path)!r}: " if path is not None else ""
            raise InputError(f"{where}reading {reader.name} files needs {mod} "
                             f"(pip install 'bvpnav[{reader.extra}]')") from None


def read(path: str | os.PathLike, input: Mapping[str, Any] | None = None) -> Recording:
    r"""Read a file with the reader its ``[input]`` names (``format``) or its suffix picks.

    Parameters
    ----------
    path : str or path-like
        The file (or folder, for folder formats); opened read-only, never modified.
    input : mapping, optional
        The spec's ``[input]`` table. ``format`` picks the reader; the strapdown keys
        (:data:`bvpnav.strapdown.FRAME_OPTIONS`) go to :meth:`Recording.imu_data`; the
        rest are the reader's own options.

    Returns
    -------
    Recording

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> tmp = tempfile.TemporaryDirectory()
    >>> path = Path(tmp.name) / "drive.csv"
    >>> _ = path.write_text("t,acc_x\n0.0,0.5\n0.1,0.5\n0.2,0.5\n")
    >>> from bvpnav.readers import read
    >>> rec = read(path)
    >>> rec.t.tolist(), rec.acc[:, 0].tolist(), rec.notes
    ([0.0, 0.1, 0.2], [0.5, 0.5, 0.5], ())
    >>> tmp.cleanup()
    """
    from ..strapdown import FRAME_OPTIONS

    opts = dict(input or {})
    p = Path(path)
    if not p.is_dir() and not p.is_file():  # missing, a FIFO, a device: named before any suffix
        from ..io import read_regular_file

        read_regular_file(p, "recording")
    reader = reader_for(p, opts.get("format"))
    mine = {k: v for k, v in opts.items() if k not in FRAME_OPTIONS and k != "format"}
    reader.check_options(mine, str(p))
    require(reader, p)
    return reader.read(p, mine)


def read_recording(path: str | os.PathLike, input: dict | None = None):
    r"""Read a recording into :class:`bvpnav.ImuData` with the reader ``[input]`` picks.

    The reader is chosen by ``input["format"]`` or the file's suffix (CSV and Parquet by
    default: :class:`bvpnav.readers.table.TableReader`, whose options and checks are listed
    there); strapdown channels become navigation-frame acceleration by the frame options
    (:mod:`bvpnav.strapdown`).

    Parameters
    ----------
    path : str or path-like
        The file; opened read-only, never modified.
    input : dict, optional
        The spec's ``[input]`` table.

    Returns
    -------
    ImuData

    Raises
    ------
    InputError
        Naming the file and the column, row or record, with the fix; also when the file
        holds information (GNSS fixes, odometry), which an ``ImuData`` cannot carry: read
        it with :func:`bvpnav.readers.read` to get ``recording.items`` too.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> tmp = tempfile.TemporaryDirectory()
    >>> path = Path(tmp.name) / "drive.csv"
    >>> _ = path.write_text("t,acc_x\n0.0,0.5\n0.1,0.5\n0.2,0.5\n")
    >>> from bvpnav.readers import read_recording
    >>> read_recording(path)
    ImuData(N=3, axes=('x',), navigation-frame, t=[0, 0.2] s)
    >>> tmp.cleanup()
    """
    rec = read(path, input)
    if rec.items:
        raise InputError(f"{str(path)!r} holds {len(rec.items)} information item(s) besides the samples "
                         f"({', '.join(sorted({type(i).__name__ for i in rec.items}))}); read_recording "
                         "returns the samples only: use rec = bvpnav.readers.read(path, input), then "
                         "rec.imu_data(input) and rec.items")
    return rec.imu_data(input)


def _origin_ns(origin: str | None) -> tuple[str, int] | None:
    """(clock kind, integer ns) of a time origin: ``("utc", ns since the Unix epoch)`` for an
    ISO timestamp with a zone (naive ones are refused by returning None), ``("<unit>", ns)``
    for a numeric origin (``"1700000000000000000 ns"``), None when it cannot be read."""
    import re

    if not isinstance(origin, str):
        return None
    m = re.fullmatch(r"(-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?) (s|ms|us|ns)", origin.strip())
    if m:  # "<integer> ns" exactly; a float origin ("1777629600.5 s") to the ns its digits say
        from decimal import Decimal

        per = {"s": 10**9, "ms": 10**6, "us": 10**3, "ns": 1}[m.group(2)]
        return "epoch", int((Decimal(m.group(1)) * per).to_integral_value())
    try:
        import pandas as pd

        ts = pd.Timestamp(origin)
    except (ValueError, TypeError):
        return None
    if ts.tzinfo is None:
        return None
    return "utc", int(ts.tz_convert("UTC").as_unit("ns").value)


def _shifted(item, dt: float):
    """A copy of ``item`` with its instants (``t``, ``t0``, ``t1``) moved by ``dt`` s."""
    import dataclasses

    import numpy as np

    changes = {f: np.asarray(getattr(item, f), dtype=float) + dt for f in ("t", "t0", "t1")
               if hasattr(item, f) and getattr(item, f) is not None}
    return dataclasses.replace(item, **changes)


def _inside(item, lo: float, hi: float):
    """(the part of ``item`` inside ``[lo, hi]``, instants dropped): rows of ``t`` outside the
    window are removed with their ``value``/``sigma`` rows; None when nothing is left."""
    import dataclasses

    import numpy as np

    if not hasattr(item, "t"):
        return item, 0
    t = np.atleast_1d(np.asarray(item.t, dtype=float))
    keep = (t >= lo) & (t <= hi)
    if keep.all():
        return item, 0
    if not keep.any():
        return None, int(t.size)
    changes = {"t": t[keep]}
    for f in ("value", "speed", "sigma"):   # speed: an Odometer's readings
        v = getattr(item, f, None)
        if v is not None and np.ndim(v) >= 1 and np.shape(v)[0] == t.size:
            changes[f] = np.asarray(v)[keep]
    return dataclasses.replace(item, **changes), int((~keep).sum())


def align(info: Recording, to: Recording, *, clock_offset: float | None = None,
          same_clock: bool = False) -> tuple[list, list[str]]:
    r"""The information items of one file on the clock of another recording.

    Parameters
    ----------
    info : Recording
        The file holding the information (an NMEA log, a bag's fixes).
    to : Recording
        The recording whose samples are solved (its ``t`` and ``time_origin``).
    clock_offset : float, optional
        Seconds to add to ``info``'s times to put them on ``to``'s: the explicit alignment
        (e.g. a GNSS log and an IMU whose clocks share nothing).
    same_clock : bool
        Both files' times are on one clock: shift by the difference of their origins.
        Needed for numeric origins (``"<n> ns"``), which may be Unix epochs or uptimes
        (with it, a numeric origin counts from the Unix epoch, so it also aligns with an ISO
        timestamp); ISO timestamps with a time zone on both sides are aligned without it.

    Returns
    -------
    (list of Item, list of str)
        The shifted items, restricted to ``to``'s window, and the notes saying what was
        done (the shift, the instants left out).

    Raises
    ------
    InputError
        When the clocks cannot be aligned from what is known (naming both origins and the
        options that would align them), and when no instant falls inside the window.

    Notes
    -----
    With origins :math:`o_i` and :math:`o_r`, an instant :math:`t_i` of ``info`` becomes
    :math:`t = t_i + (o_i - o_r)` (in integer nanoseconds, then seconds), or
    :math:`t = t_i + \text{clock\_offset}`.

    Examples
    --------
    GNSS fixes whose clock starts 3 s after the IMU's: their instants move by +3 s, and the
    one that falls after the IMU's 10 s window is left out (and said so):

    >>> import numpy as np
    >>> from bvpnav.constraints import Position
    >>> from bvpnav.readers import Recording, align
    >>> imu = Recording(t=np.linspace(0.0, 10.0, 101), source="imu", time_origin="2026-05-01T10:00:00Z",
    ...                 acc=np.zeros((101, 1)), axes=("x",))
    >>> fixes = Position(t=[0.0, 5.0, 20.0], value=[1.0, 2.0, 3.0], sigma=1.0)
    >>> gnss = Recording(t=np.array([0.0, 5.0, 20.0]), source="gnss", time_origin="2026-05-01T10:00:03Z",
    ...                  items=(fixes,))
    >>> items, notes = align(gnss, imu)
    >>> items[0].t.tolist(), items[0].value.tolist()
    ([3.0, 8.0], [1.0, 2.0])
    >>> print(notes[0])
    gnss: times shifted by +3.000000000 s (origin 2026-05-01T10:00:03Z -> 2026-05-01T10:00:00Z)
    """
    notes: list[str] = []
    if clock_offset is not None and same_clock:
        raise InputError("give either clock_offset (seconds between the clocks) or same_clock, not both")
    if clock_offset is not None:
        dt = float(clock_offset)
        notes.append(f"{info.source}: times shifted by the given clock offset {dt:+.9g} s")
    else:
        a, b = _origin_ns(info.time_origin), _origin_ns(to.time_origin)
        both_utc = a is not None and b is not None and a[0] == b[0] == "utc"
        if a is None or b is None or (not both_utc and not same_clock):
            raise InputError(
                f"cannot put {info.source} (t = 0 at {info.time_origin!r}) on the clock of {to.source} "
                f"(t = 0 at {to.time_origin!r}): their clocks are not known to be one. Give the offset "
                "(--clock-offset SECONDS: added to the information's times), or --same-clock when both "
                "count from one epoch (e.g. both Unix-epoch nanoseconds); ISO timestamps with a time zone "
                "are aligned by themselves")
        dt = (a[1] - b[1]) * 1e-9
        notes.append(f"{info.source}: times shifted by {dt:+.9f} s (origin {info.time_origin} -> "
                     f"{to.time_origin})")
    lo, hi = float(to.t[0]), float(to.t[-1])
    out, dropped, total = [], 0, 0
    for item in info.items:
        moved = _shifted(item, dt)
        kept, gone = _inside(moved, lo, hi)
        total += int(getattr(moved, "t", [0]).size) if hasattr(moved, "t") else 1
        dropped += gone
        if kept is not None:
            out.append(kept)
    if dropped:
        notes.append(f"{info.source}: {dropped} of {total} instant(s) lie outside the recording's window "
                     f"[{lo:.6g}, {hi:.6g}] s and are left out")
    if not out and info.items:
        raise InputError(f"{info.source}: no instant of its {len(info.items)} item(s) falls inside the "
                         f"recording's window [{lo:.6g}, {hi:.6g}] s after the shift of {dt:+.6g} s; check "
                         "the clock offset")
    return out, notes
