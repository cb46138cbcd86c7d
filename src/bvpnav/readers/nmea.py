r"""NMEA 0183 logs (GGA, RMC, GST, VTG sentences of any talker): GNSS fixes as information.

A GNSS receiver's log holds no IMU samples: the reader returns an *information-only*
:class:`~bvpnav.readers.Recording` (``acc`` and ``specific_force`` both None,
:attr:`~bvpnav.readers.Recording.is_information`) whose ``items`` are

- one soft :class:`~bvpnav.constraints.Position` item with the GGA fixes, converted to a
  local ENU or NED frame about a geodetic origin (:func:`bvpnav.geodesy.geodetic_to_local`);
- one soft horizontal :class:`~bvpnav.constraints.Velocity` item from the RMC speed and
  course over ground, when the log has RMC sentences; or, with ``speed_as = "odometer"``,
  one soft :class:`~bvpnav.constraints.Odometer` item from the speed over ground of the RMC
  and VTG sentences (no course needed).

Options (the spec's ``[input]``):

``origin``
    ``"first"`` (default: the first valid fix) or ``[lat, lon, h]`` (degrees, degrees, m
    above the WGS-84 ellipsoid). The origin used is in ``meta["geodetic_origin"]``.
``local_frame``
    ``"enu"`` (default; x east, y north, z up) or ``"ned"`` (x north, y east, z down): the
    frame of the items, the same as the IMU recording's ``frame``.
``uere``
    User equivalent range error in m, default 5.0 (a standalone single-frequency receiver;
    about 1 for SBAS/DGPS, a few cm for RTK fixed).
``vertical_factor``
    Vertical sigma over ``HDOP * uere``, default 1.5 (a typical VDOP/HDOP ratio).
``sigma_source``
    ``"auto"`` (default: the GST sentence's latitude/longitude/altitude sigmas when the fix
    has one, else HDOP) or ``"hdop"``.
``velocity``
    Whether RMC speed/course become a Velocity item (default true).
``velocity_sigma``
    Sigma of each horizontal velocity component in m/s, default 0.2 (also the sigma of the
    speeds over ground with ``speed_as = "odometer"``).
``speed_as``
    ``"velocity"`` (default: RMC speed and course as a horizontal Velocity item) or
    ``"odometer"``: the speed over ground of RMC and VTG sentences (VTG on the time of the
    epoch's GGA/RMC sentence before it; an RMC at the same time wins) as an
    :class:`~bvpnav.constraints.Odometer` item along body x with ``scaled = False`` (a GNSS
    speed has no scale error), at the point ``odometer_lever`` ([x, y, z] in m, body axes:
    the antenna's offset from the IMU; default the IMU). The speed over ground is the
    antenna's horizontal speed, unsigned: taken as the forward speed it neglects sideslip,
    the slope (a factor cos(climb): 0.2 % on a 6 % grade) and reversing.
``odometer_lever``
    See ``speed_as``.
``date``
    ``"YYYY-MM-DD"``, the UTC date of the first fix, for logs without RMC dates (or a
    check of them). Without any date ``t = 0`` is the first fix's time of day and
    ``time_origin`` is None.
``skip_bad_lines``
    Default false: a line that does not parse or fails its checksum is refused with its
    line number. True skips such lines and counts them in ``notes``.

Sigma from HDOP (the DOP definition :math:`\sigma_E^2 + \sigma_N^2 = HDOP^2 \sigma_{UERE}^2`):
:math:`\sigma_x = \sigma_y = HDOP \cdot uere / \sqrt 2` per horizontal axis and
:math:`\sigma_z = vertical\_factor \cdot HDOP \cdot uere`.

Times are UTC: the GGA/RMC time of day, the date from RMC (or ``date``), a day added each
time the time of day falls back by more than 12 h (midnight rollover). ``t`` is in s from
the first fix, ``time_origin`` that instant in ISO 8601 (``"...Z"``).

Heights are above the ellipsoid: GGA altitude (mean sea level) plus its geoid separation.
Fixes with quality 0 (no fix), 6 (estimated), 7 (manual) or 8 (simulation), and fixes
missing a field, are dropped and counted in ``notes``.
"""

from __future__ import annotations

import datetime as _dt
import math
import re
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import InputError
from . import Reader, Recording, register_reader

__all__ = ["NmeaReader", "checksum", "sentence", "format_gga", "format_rmc", "format_gst",
           "example_lines", "EXAMPLE"]

KNOT = 1852.0 / 3600.0  # m/s
DAY_NS = 86_400 * 10**9
_EPOCH = _dt.date(1970, 1, 1).toordinal()
_GOOD_QUALITY = {1: "GPS", 2: "DGPS", 3: "PPS", 4: "RTK fixed", 5: "RTK float"}
_DROP_QUALITY = {0: "no fix", 6: "estimated", 7: "manual input", 8: "simulation"}
_SENTENCE = re.compile(rb"^\$[A-Z][A-Z0-9]{4,}[,*]")
_FIX = re.compile(rb"^\$[A-Z]{2}(GGA|RMC),[^\r\n]*\*[0-9A-Fa-f]{2}\s*$")


# ------------------------------------------------------------------ writing (examples, tests)
def checksum(body: str) -> str:
    """The NMEA checksum of ``body`` (the text between ``$`` and ``*``): two hex digits."""
    x = 0
    for ch in body:
        x ^= ord(ch)
    return f"{x:02X}"


def sentence(body: str) -> str:
    """``$<body>*<checksum>``, one NMEA 0183 sentence (without line ending)."""
    return f"${body}*{checksum(body)}"


def _dm(value: float, deg_digits: int, hemis: str) -> tuple[str, str]:
    v = abs(float(value))
    deg = int(v)
    minutes = round((v - deg) * 60.0, 7)
    if minutes >= 60.0:
        deg, minutes = deg + 1, 0.0
    return f"{deg:0{deg_digits}d}{minutes:010.7f}", hemis[0] if value >= 0 else hemis[1]


def _hms(tod_s: float) -> str:
    tod_s = float(tod_s) % 86400.0
    h, rest = divmod(round(tod_s * 100), 360000)
    m, cs = divmod(rest, 6000)
    return f"{h:02d}{m:02d}{cs // 100:02d}.{cs % 100:02d}"


def format_gga(tod_s: float, lat: float, lon: float, height: float, *, geoid: float = 0.0,
               quality: int = 1, satellites: int = 10, hdop: float = 1.0, talker: str = "GP") -> str:
    """A GGA sentence for a fix.

    Parameters
    ----------
    tod_s : float
        UTC time of day in s (written to 0.01 s).
    lat, lon : float
        Degrees (written to 1e-7 arc minutes, about 0.2 mm).
    height : float
        Height above the WGS-84 ellipsoid in m; the sentence holds ``height - geoid``
        (mean sea level) and the geoid separation ``geoid``, to 1 mm.
    geoid, quality, satellites, hdop, talker
        Geoid separation (m), fix quality, satellites used, HDOP, talker id.
    """
    la, ns = _dm(lat, 2, "NS")
    lo, ew = _dm(lon, 3, "EW")
    return sentence(f"{talker}GGA,{_hms(tod_s)},{la},{ns},{lo},{ew},{quality:d},{satellites:02d},"
                    f"{hdop:.2f},{height - geoid:.3f},M,{geoid:.3f},M,,")


def format_rmc(tod_s: float, date: _dt.date, lat: float, lon: float, speed: float, course: float, *,
               status: str = "A", talker: str = "GP") -> str:
    """An RMC sentence: UTC time of day (s), date, position (degrees), speed over ground
    (m/s, written in knots) and course over ground (degrees from true north)."""
    la, ns = _dm(lat, 2, "NS")
    lo, ew = _dm(lon, 3, "EW")
    return sentence(f"{talker}RMC,{_hms(tod_s)},{status},{la},{ns},{lo},{ew},{speed / KNOT:.4f},"
                    f"{course % 360.0:.3f},{date:%d%m%y},,,A")


def format_gst(tod_s: float, sd_lat: float, sd_lon: float, sd_alt: float, *, talker: str = "GP") -> str:
    """A GST sentence with the latitude, longitude and altitude error sigmas in m."""
    rms = math.sqrt(sd_lat**2 + sd_lon**2)
    return sentence(f"{talker}GST,{_hms(tod_s)},{rms:.3f},{max(sd_lat, sd_lon):.3f},"
                    f"{min(sd_lat, sd_lon):.3f},0.0,{sd_lat:.3f},{sd_lon:.3f},{sd_alt:.3f}")


# ------------------------------------------------------------------ reading
@dataclass(frozen=True)
class _Line:
    no: int
    kind: str  # GGA, RMC, GST
    tod_ns: int
    data: tuple[str, ...]
    latlon: tuple[float, float] | None  # degrees, when the sentence has a position
    talker: str


#: Fields a sentence needs (GGA up to the geoid separation, RMC up to the date, GST all).
_FIELDS = {"GGA": 11, "RMC": 9, "GST": 8, "VTG": 7}
_LATLON = {"GGA": 1, "RMC": 2}  # index of the latitude field


def _angle(field: str, hemi: str, deg_digits: int, limit: float, hemis: str) -> float:
    m = re.fullmatch(r"(\d{" + str(deg_digits) + r"})(\d{2}(?:\.\d*)?)", field)
    if not m or hemi not in hemis or float(m[2]) >= 60.0:
        raise ValueError(f"{field!r},{hemi!r} is not a {'latitude' if limit == 90 else 'longitude'} "
                         f"({'d' * deg_digits}mm.mmm,{hemis[0]}|{hemis[1]})")
    v = int(m[1]) + float(m[2]) / 60.0
    if v > limit:
        raise ValueError(f"{field!r},{hemi!r}: {v!r} degrees is beyond {limit:g}")
    return v if hemi == hemis[0] else -v


def _position(kind: str, data: tuple[str, ...]) -> tuple[float, float] | None:
    """(lat, lon) in degrees of a GGA/RMC sentence; None when the fields are empty."""
    if kind not in _LATLON:
        return None
    i = _LATLON[kind]
    if not (data[i] or data[i + 2]):
        return None
    return _angle(data[i], data[i + 1], 2, 90.0, "NS"), _angle(data[i + 2], data[i + 3], 3, 180.0, "EW")


def _tod_ns(field: str) -> int:
    """``hhmmss[.sss]`` to integer nanoseconds of the day (ValueError if malformed)."""
    m = re.fullmatch(r"(\d{2})(\d{2})(\d{2})(?:\.(\d{1,9}))?", field)
    if not m:
        raise ValueError(f"time field {field!r} is not hhmmss.ss")
    h, mi, s = int(m[1]), int(m[2]), int(m[3])
    if h > 23 or mi > 59 or s > 60:
        raise ValueError(f"time field {field!r} is not a time of day")
    frac = int((m[4] or "").ljust(9, "0"))
    return ((h * 60 + mi) * 60 + s) * 10**9 + frac


def _date(field: str, what: str) -> _dt.date:
    m = re.fullmatch(r"(\d{2})(\d{2})(\d{2})", field)
    if not m:
        raise ValueError(f"{what} date field {field!r} is not ddmmyy")
    yy = int(m[3])
    try:
        return _dt.date(2000 + yy if yy < 80 else 1900 + yy, int(m[2]), int(m[1]))
    except ValueError:
        raise ValueError(f"{what} date field {field!r} is not a valid date (ddmmyy)") from None


@dataclass
class _Scan:
    lines: list
    ignored: Counter
    bad: list


def _scan(path: Path, text: str, skip_bad: bool, vtg: bool = False) -> _Scan:
    """Every GGA/RMC/GST sentence (and VTG when ``vtg``), checksum verified; other sentences
    counted. A VTG (no time field) takes the time of the sentence before it; one before any
    timed sentence is counted among the ignored."""
    import pynmea2

    out = _Scan([], Counter(), [])
    for no, raw in enumerate(text.splitlines(), 1):
        line = raw.strip()
        if not line:
            continue
        try:
            if "\ufffd" in line or not line.isascii():
                raise ValueError("not ASCII text")
            try:
                msg = pynmea2.parse(line, check=True)
            except pynmea2.SentenceTypeError:
                body, _, cs = line[1:].partition("*")
                if not line.startswith("$") or checksum(body) != cs.strip().upper():
                    raise ValueError("not an NMEA sentence with a valid checksum") from None
                out.ignored[body.split(",")[0][2:] or "?"] += 1
                continue
            kind = getattr(msg, "sentence_type", None)
            if kind not in _FIELDS or (kind == "VTG" and not (vtg and out.lines)):
                late = " before any timed sentence" if kind == "VTG" and vtg else ""
                out.ignored[(kind or type(msg).__name__) + late] += 1
                continue
            data = tuple(str(d) for d in msg.data)
            if len(data) < _FIELDS[kind]:
                raise ValueError(f"a {kind} sentence has at least {_FIELDS[kind]} fields, this one "
                                 f"{len(data)}")
            tod = out.lines[-1].tod_ns if kind == "VTG" else _tod_ns(data[0])
            out.lines.append(_Line(no, kind, tod, data, _position(kind, data), msg.talker))
        except (pynmea2.ParseError, ValueError, IndexError) as exc:
            reason = exc.args[0] if exc.args and isinstance(exc.args[0], str) else str(exc)
            reason = "bad checksum (" + reason + ")" if isinstance(exc, pynmea2.ChecksumError) else reason
            if not skip_bad:
                raise InputError(f"{path}: line {no}: {reason}: {line[:90]!r}. Repair or delete the line, or "
                                 "set [input] skip_bad_lines = true to skip such lines (counted in the "
                                 "recording's notes)") from None
            out.bad.append((no, reason))
    return out


def _day_index(path: Path, lines: list) -> tuple[list[int], int]:
    """Days since the first sentence's day, from midnight rollovers; the rollover count."""
    days, day, prev = [], 0, None
    for ln in lines:
        if prev is not None and ln.tod_ns < prev.tod_ns:
            if prev.tod_ns - ln.tod_ns <= DAY_NS // 2:
                raise InputError(f"{path}: line {ln.no}: time {_clock(ln.tod_ns)} UTC is before line "
                                 f"{prev.no}'s {_clock(prev.tod_ns)}; the log is out of order (sort it by "
                                 "time, or cut it where the clock jumps back)")
            day += 1
        days.append(day)
        prev = ln
    return days, day


def _clock(ns: int) -> str:
    s = ns / 1e9
    return f"{int(s // 3600):02d}:{int(s % 3600 // 60):02d}:{s % 60:06.3f}"


def _base_date(path: Path, lines: list, days: list[int], option: Any) -> _dt.date | None:
    """The UTC date of day index 0: from the RMC dates (all consistent) and/or ``date``."""
    base, where = None, None
    if option is not None:
        try:
            base, where = _dt.date.fromisoformat(str(option)), "[input] date"
        except ValueError:
            raise InputError(f"{path}: [input] date = {option!r}: give the UTC date of the first fix as "
                             "\"YYYY-MM-DD\"") from None
    for ln, d in zip(lines, days, strict=True):
        if ln.kind != "RMC" or not ln.data[8]:
            continue
        try:
            date = _date(ln.data[8], "RMC")
        except ValueError as exc:
            raise InputError(f"{path}: line {ln.no}: {exc}; repair or delete the line") from None
        implied = _dt.date.fromordinal(date.toordinal() - d)
        if base is None:
            base, where = implied, f"the RMC date of line {ln.no}"
        elif implied != base:
            raise InputError(f"{path}: line {ln.no}: the RMC date {date} disagrees with {where} "
                             f"(the times imply {_dt.date.fromordinal(base.toordinal() + d)}): a gap of a "
                             "day or more, or a wrong [input] date; cut the log there or fix the date")
    return base


def _float(field: str) -> float | None:
    try:
        v = float(field)
    except ValueError:
        return None
    return v if math.isfinite(v) else None


def _fix(ln: _Line, drops: Counter) -> tuple[float, float, float, float | None] | None:
    """(lat, lon, ellipsoidal height, hdop) of a usable GGA fix, or None (counted in ``drops``)."""
    d = ln.data
    q = int(d[5]) if d[5].isdigit() else 0
    if q not in _GOOD_QUALITY:
        drops[f"quality {q} ({_DROP_QUALITY.get(q, 'unknown')})"] += 1
        return None
    if ln.latlon is None or _float(d[8]) is None:
        drops["no latitude, longitude or altitude"] += 1
        return None
    sep = _float(d[10])
    if sep is None:
        drops["__no_geoid"] += 1
    hdop = _float(d[7])
    return *ln.latlon, _float(d[8]) + (sep or 0.0), hdop if hdop and hdop > 0 else None


def _gst_sigmas(ln: _Line) -> tuple[float, float, float] | None:
    vals = [_float(v) for v in ln.data[5:8]] if len(ln.data) >= 8 else []
    if len(vals) == 3 and all(v is not None and v > 0 for v in vals):
        return vals[0], vals[1], vals[2]
    return None


def _velocity(ln: _Line, drops: Counter, times: list[int], n: int) -> tuple[float, float] | None:
    """(v_east, v_north) in m/s of a valid RMC at ``n`` ns after ``times``, or None (counted
    in ``drops``)."""
    d = ln.data
    if times and n <= times[-1]:
        drops["repeated time"] += 1
        return None
    if d[1] != "A" or (len(d) > 11 and d[11] == "N"):
        drops["status void"] += 1
        return None
    speed, course = _float(d[6]), _float(d[7])
    if speed is None or (course is None and speed != 0.0):
        drops["no speed or course"] += 1
        return None
    speed *= KNOT
    c = math.radians(course or 0.0)
    return speed * math.sin(c), speed * math.cos(c)


def _ground_speed(ln: _Line, drops: Counter, times: list[int], n: int) -> float | None:
    """The speed over ground in m/s of a valid RMC or VTG at ``n`` ns after ``times``, or None
    (counted in ``drops``; a malformed speed field is refused naming the line)."""
    d = ln.data
    if times and n <= times[-1]:
        drops["repeated time"] += 1
        return None
    if ln.kind == "RMC":
        void = d[1] != "A" or (len(d) > 11 and d[11] == "N")
        field, unit = d[6], KNOT
    else:   # VTG: km/h (field 7) if given, else knots (field 5); mode N: not valid
        void = len(d) > 8 and d[8] == "N"
        field, unit = (d[6], 1.0 / 3.6) if d[6] else (d[4], KNOT)
    if void:
        drops["status void"] += 1
        return None
    if not field:
        drops["no speed"] += 1
        return None
    v = _float(field)
    if v is None or v < 0:
        raise ValueError(f"line {ln.no}: the {ln.kind} speed over ground {field!r} is not a speed (a number "
                         ">= 0)")
    return v * unit


def _choice(options: Mapping[str, Any], key: str, default: Any, valid: tuple, path: Path) -> Any:
    v = options.get(key, default)
    if v not in valid or isinstance(v, bool) != isinstance(default, bool):
        raise InputError(f"{path}: [input] {key} = {v!r}: valid values {list(valid)}")
    return v


def _positive(options: Mapping[str, Any], key: str, default: float, units: str, path: Path) -> float:
    v = options.get(key, default)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v > 0):
        raise InputError(f"{path}: [input] {key} = {v!r}: a positive number in {units} (default {default})")
    return float(v)


@dataclass(frozen=True)
class _Settings:
    frame: str
    uere: float
    vertical: float
    source: str
    velocity: bool
    velocity_sigma: float
    skip_bad: bool
    speed_as: str = "velocity"
    lever: tuple = (0.0, 0.0, 0.0)


def _settings(options: Mapping[str, Any], path: Path) -> _Settings:
    return _Settings(
        frame=_choice(options, "local_frame", "enu", ("enu", "ned"), path),
        uere=_positive(options, "uere", 5.0, "m", path),
        vertical=_positive(options, "vertical_factor", 1.5, "(a ratio)", path),
        source=_choice(options, "sigma_source", "auto", ("auto", "hdop"), path),
        velocity=_choice(options, "velocity", True, (True, False), path),
        velocity_sigma=_positive(options, "velocity_sigma", 0.2, "m/s", path),
        skip_bad=_choice(options, "skip_bad_lines", False, (True, False), path),
        speed_as=_choice(options, "speed_as", "velocity", ("velocity", "odometer"), path),
        lever=_lever(options, path),
    )


def _lever(options: Mapping[str, Any], path: Path) -> tuple:
    v = options.get("odometer_lever", [0.0, 0.0, 0.0])
    ok = (isinstance(v, (list, tuple)) and len(v) == 3
          and all(isinstance(a, (int, float)) and not isinstance(a, bool) and math.isfinite(a) for a in v))
    if not ok:
        raise InputError(f"{path}: [input] odometer_lever = {v!r}: give [x, y, z], the antenna's position "
                         "relative to the IMU in body axes, m")
    return tuple(float(a) for a in v)


def _origin_option(options: Mapping[str, Any], first: tuple[float, float, float], path: Path):
    from ..geodesy import _origin

    v = options.get("origin", "first")
    if isinstance(v, str) and v == "first":
        return first, "the first valid fix"
    if isinstance(v, str) or isinstance(v, bool):
        raise InputError(f"{path}: [input] origin = {v!r}: give \"first\" or [lat, lon, h] (degrees, "
                         "degrees, m above the WGS-84 ellipsoid)")
    try:
        return _origin(v), "[input] origin"
    except InputError as exc:
        raise InputError(f"{path}: [input] {exc}") from None


def _count(c: Counter) -> str:
    return ", ".join(f"{n} {k}" for k, n in sorted(c.items()))


def _epoch_ns(base: _dt.date | None, day: int, tod: int) -> int:
    return ((base.toordinal() - _EPOCH) if base is not None else 0) * DAY_NS + day * DAY_NS + tod


class NmeaReader(Reader):
    """NMEA 0183 GNSS logs: GGA fixes (and RMC velocities) as information-only items.

    See the module docstring (:mod:`bvpnav.readers.nmea`) for the options, the sigma model
    and the time convention.
    """

    name = "nmea"
    suffixes = (".nmea", ".nma", ".gps")
    options = frozenset({"origin", "local_frame", "uere", "vertical_factor", "sigma_source", "velocity",
                         "velocity_sigma", "date", "skip_bad_lines", "speed_as", "odometer_lever"})
    modules = ("pynmea2", "pymap3d")
    extra = "gnss"
    description = ("NMEA 0183 GNSS log (GGA fixes, RMC speed/course): Position and Velocity items, "
                   "no IMU samples")

    def sniff(self, head: bytes) -> bool:
        """Strict: most non-empty lines are ``$``-sentences and at least one is a
        checksummed GGA or RMC sentence."""
        lines = [ln.strip() for ln in head.lstrip(b"\xef\xbb\xbf").splitlines()[:-1] or head.splitlines()]
        lines = [ln for ln in lines if ln]
        if not lines:
            return False
        nmea = sum(1 for ln in lines if _SENTENCE.match(ln))
        return nmea >= 0.8 * len(lines) and any(_FIX.match(ln) for ln in lines)

    def read(self, path: Path, options: Mapping[str, Any]) -> Recording:
        import numpy as np

        from ..geodesy import geodetic_to_local

        path = Path(path)
        cfg = _settings(options, path)
        try:
            text = path.read_bytes().decode("ascii", errors="replace")
        except OSError as exc:
            raise InputError(f"{path}: cannot read the file ({exc.strerror})") from None
        scan = _scan(path, text, cfg.skip_bad, vtg=cfg.speed_as == "odometer" and cfg.velocity)
        lines = scan.lines
        days, rollovers = _day_index(path, lines)
        base = _base_date(path, lines, days, options.get("date"))
        ns = [_epoch_ns(base, d, ln.tod_ns) for ln, d in zip(lines, days, strict=True)]
        gst = {n: s for ln, n in zip(lines, ns, strict=True) if ln.kind == "GST" and (s := _gst_sigmas(ln))}
        drops, vdrops = Counter(), Counter()
        fixes, ft, vel, vt, last = [], [], [], [], None
        for ln, n in zip(lines, ns, strict=True):
            if ln.kind == "GGA" and (f := _fix(ln, drops)) is not None:
                if last is not None and n <= last[1]:
                    raise InputError(f"{path}: line {ln.no}: a second fix at {_clock(ln.tod_ns)} UTC (line "
                                     f"{last[0]} has one at or after it); remove the duplicate")
                sig = gst.get(n) if cfg.source == "auto" else None
                if sig is None and f[3] is None:
                    drops["no HDOP (and no GST)"] += 1
                    continue
                fixes.append((*f[:3], f[3], sig))
                ft.append(n)
                last = (ln.no, n)
            elif cfg.speed_as == "odometer" and ln.kind in ("RMC", "VTG") and cfg.velocity:
                try:
                    v = _ground_speed(ln, vdrops, vt, n)
                except ValueError as exc:
                    raise InputError(f"{path}: {exc}; repair or delete the line") from None
                if v is not None:
                    vel.append(v)
                    vt.append(n)
            elif ln.kind == "RMC" and cfg.velocity and (v := _velocity(ln, vdrops, vt, n)) is not None:
                vel.append(v)
                vt.append(n)
        if not fixes:
            raise InputError(f"{path}: no usable GGA fix ({_count(drops) or 'no GGA sentence'}); an NMEA log "
                             "needs GGA sentences with a fix (quality 1-5)")
        arr = np.array([f[:3] for f in fixes])
        origin, origin_from = _origin_option(options, tuple(float(v) for v in arr[0]), path)
        xyz = geodetic_to_local(arr[:, 0], arr[:, 1], arr[:, 2], origin, cfg.frame)
        sigma = np.array([self._sigma(f, cfg) for f in fixes])
        n0 = ft[0]
        t_fix = (np.asarray(ft, dtype=np.int64) - n0) * 1e-9
        items = [self._position(t_fix, xyz, sigma, path)]
        keep = [i for i, n in enumerate(vt) if n >= n0]
        if cfg.speed_as == "odometer" and cfg.velocity and not keep:
            why = _count(vdrops) or "no RMC or VTG sentence"
            raise InputError(f"{path}: [input] speed_as = \"odometer\", but the log has no usable speed over "
                             f"ground in RMC or VTG sentences at or after the first fix ({why}); drop "
                             "speed_as or give a log with them")
        if keep:
            vv = np.array([vel[i] for i in keep])
            t_vel = (np.asarray([vt[i] for i in keep], dtype=np.int64) - n0) * 1e-9
            if cfg.speed_as == "odometer":
                items.append(self._speed_item(t_vel, vv, cfg, path))
            else:
                vv = vv if cfg.frame == "enu" else vv[:, ::-1]
                items.append(self._velocity_item(t_vel, vv, cfg.velocity_sigma, path))
        t = np.union1d(t_fix, t_vel) if keep else t_fix
        origin_iso = (str(np.datetime64(int(n0), "ns")) + "Z") if base is not None else None
        notes = self._notes(path, cfg, scan, drops, vdrops, len(fixes), len(keep), len(vt) - len(keep),
                            origin, origin_from, sum(f[4] is not None for f in fixes), origin_iso,
                            _clock(n0 % DAY_NS), rollovers)
        meta = {"geodetic_origin": list(origin), "frame": cfg.frame, "n_fixes": len(fixes),
                "talkers": sorted({ln.talker for ln in lines})}
        return Recording(t=t, source=str(path), time_origin=origin_iso, items=tuple(items),
                         notes=tuple(notes), meta=meta)

    @staticmethod
    def _sigma(fix: tuple, cfg: _Settings) -> tuple[float, float, float]:
        if fix[4] is not None:  # GST: latitude, longitude, altitude sigmas
            s_lat, s_lon, s_alt = fix[4]
            return (s_lon, s_lat, s_alt) if cfg.frame == "enu" else (s_lat, s_lon, s_alt)
        sh = fix[3] * cfg.uere
        return sh / math.sqrt(2.0), sh / math.sqrt(2.0), cfg.vertical * sh

    @staticmethod
    def _position(t, xyz, sigma, path: Path):
        from ..constraints import Position

        return Position(t=t, value=xyz, axes=("x", "y", "z"), sigma=sigma, name=f"{path.name} fixes")

    @staticmethod
    def _velocity_item(t, v, sigma: float, path: Path):
        from ..constraints import Velocity

        return Velocity(t=t, value=v, axes=("x", "y"), sigma=sigma, name=f"{path.name} velocity")

    @staticmethod
    def _speed_item(t, speed, cfg: _Settings, path: Path):
        from ..constraints import Odometer

        return Odometer(t=t, speed=speed, sigma=cfg.velocity_sigma, lever=cfg.lever, scaled=False,
                        name=f"{path.name} speed over ground")

    @staticmethod
    def _notes(path, cfg, scan, drops, vdrops, n_fix, n_vel, n_vel_before, origin, origin_from, n_gst,
               origin_iso, first_clock, rollovers) -> list[str]:
        no_geoid = drops.pop("__no_geoid", 0)
        notes = [f"{n_fix} GGA fixes of {path.name} as a soft Position item in the local {cfg.frame.upper()} "
                 f"frame about the geodetic origin (lat, lon, h) = ({origin[0]:.9f}, {origin[1]:.9f}, "
                 f"{origin[2]:.3f}) (degrees, degrees, m above the WGS-84 ellipsoid; {origin_from})."]
        notes.append(f"Fix sigmas: {n_fix - n_gst} from HDOP (x, y: HDOP * uere / sqrt(2), z: "
                     f"{cfg.vertical:g} * HDOP * uere, uere = {cfg.uere:g} m), {n_gst} from GST sentences.")
        if origin_iso is not None:
            notes.append(f"t = 0 is the first fix, {origin_iso} (UTC).")
        else:
            notes.append(f"t = 0 is the first fix at {first_clock} UTC on an unknown date (no RMC date): "
                         "time_origin is None; set [input] date = \"YYYY-MM-DD\" to state it.")
        if rollovers:
            notes.append(f"The times cross midnight UTC {rollovers} time(s): a day added at each rollover.")
        if no_geoid:
            notes.append(f"{no_geoid} fixes have no geoid separation: their height is the altitude above "
                         "mean sea level, not above the ellipsoid.")
        if drops:
            notes.append(f"Dropped GGA sentences: {_count(drops)}.")
        odo = cfg.speed_as == "odometer"
        if n_vel and odo:
            notes.append(f"{n_vel} RMC/VTG speeds over ground as a soft Odometer item along body x at the "
                         f"lever {list(cfg.lever)} m (scaled = false), sigma {cfg.velocity_sigma:g} m/s: "
                         "taken as the forward speed, neglecting sideslip, the slope and reversing.")
        elif n_vel:
            notes.append(f"{n_vel} RMC speeds and courses over ground as a soft horizontal Velocity item "
                         f"(axes x, y of {cfg.frame.upper()}), sigma {cfg.velocity_sigma:g} m/s per axis.")
        if vdrops or n_vel_before:
            extra = dict(vdrops)
            if n_vel_before:
                extra["before the first fix"] = n_vel_before
            what = "RMC/VTG speeds" if odo else "RMC velocities"
            notes.append(f"Dropped {what}: {_count(Counter(extra))}.")
        if scan.ignored:
            read = "GGA, RMC, GST and VTG" if odo and cfg.velocity else "GGA, RMC and GST"
            notes.append(f"Ignored sentences (only {read} are read): {_count(scan.ignored)}.")
        if scan.bad:
            shown = "; ".join(f"line {no}: {why}" for no, why in scan.bad[:5])
            more = f" and {len(scan.bad) - 5} more" if len(scan.bad) > 5 else ""
            notes.append(f"Skipped {len(scan.bad)} bad lines (skip_bad_lines = true): {shown}{more}.")
        return notes

    def example(self, folder: Path) -> Path:
        """Eleven 1 Hz epochs (GGA + RMC, one GSV) of a car driving north-east near Munich,
        written from known positions with correct checksums."""
        path = Path(folder) / "gnss.nmea"
        path.write_text("".join(line + "\r\n" for line in example_lines()))
        return path


#: The example's truth: origin (lat, lon, h), velocity east/north in m/s, date, start time of day.
EXAMPLE = {"origin": (48.1173, 11.5167, 520.0), "velocity": (8.0, 6.0), "date": _dt.date(2026, 5, 1),
           "start": 36000.0, "n": 11, "geoid": 47.0, "hdop": 0.9}


def example_lines(start: float | None = None, n: int | None = None) -> list[str]:
    """The example log's sentences (GGA + RMC per epoch; one GSV), from :data:`EXAMPLE`'s
    straight-line motion on a flat local ENU frame converted with pymap3d."""
    import numpy as np

    from ..geodesy import local_to_geodetic

    e = EXAMPLE
    start = e["start"] if start is None else start
    n = e["n"] if n is None else n
    k = np.arange(n, dtype=float)
    ve, vn = e["velocity"]
    enu = np.column_stack([ve * k, vn * k, np.zeros(n)])
    lat, lon, h = local_to_geodetic(enu, e["origin"], "enu")
    speed, course = math.hypot(ve, vn), math.degrees(math.atan2(ve, vn))
    out = [sentence("GPGSV,1,1,04,03,45,111,40,04,60,270,42,06,30,010,38,13,20,292,35")]
    for i in range(n):
        tod = start + i
        day = e["date"] + _dt.timedelta(days=int(tod // 86400))
        out.append(format_gga(tod, lat[i], lon[i], h[i], geoid=e["geoid"], hdop=e["hdop"], talker="GN"))
        out.append(format_rmc(tod, day, lat[i], lon[i], speed, course, talker="GN"))
    return out


register_reader(NmeaReader())
