"""WGS-84 geodesy for GNSS information: local frames, normal gravity, fixes as items.

bvpnav solves in a flat local navigation frame; GNSS receivers give geodetic
coordinates (latitude, longitude, height above the WGS-84 ellipsoid). This module
converts between the two about a stated geodetic origin, in the frames of
:mod:`bvpnav.strapdown`:

- ``"enu"``: x = east, y = north, z = up;
- ``"ned"``: x = north, y = east, z = down.

The geodesy itself (geodetic -> ECEF -> local tangent plane, and back) is done by
`pymap3d <https://github.com/geospace-code/pymap3d>`_, an optional dependency
(``pip install 'bvpnav[gnss]'``), imported only when a conversion is asked for.
:func:`normal_gravity` needs nothing beyond the standard library.

Angles are in degrees, lengths in m, heights above the WGS-84 ellipsoid (not above
mean sea level: a GGA sentence's altitude plus its geoid separation).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .errors import InputError

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd

    from .constraints import Position

__all__ = [
    "STANDARD_GRAVITY",
    "WGS84",
    "geodetic_to_local",
    "local_to_geodetic",
    "normal_gravity",
    "position_items",
    "trajectory_to_geodetic",
]

#: Standard gravity, m/s^2 (the conventional value, CGPM 1901).
STANDARD_GRAVITY = 9.80665

#: WGS-84 defining and derived constants (NIMA TR8350.2, 3rd ed., tables 3.1-3.3).
WGS84 = {
    "a": 6378137.0,                    # semi-major axis, m
    "f": 1.0 / 298.257223563,          # flattening
    "gm": 3.986004418e14,              # Earth's gravitational constant, m^3/s^2
    "omega": 7.292115e-5,              # angular velocity, rad/s
    "b": 6356752.3142,                 # semi-minor axis, m
    "e2": 6.69437999014e-3,            # first eccentricity squared
    "gamma_e": 9.7803253359,           # normal gravity at the equator, m/s^2
    "gamma_p": 9.8321849378,           # normal gravity at the poles, m/s^2
    "k": 0.00193185265241,             # Somigliana's constant b*gamma_p/(a*gamma_e) - 1
    "m": 0.00344978650684,             # omega^2 a^2 b / GM
}

_FRAMES = ("enu", "ned")
_INSTALL = "pip install 'bvpnav[gnss]'"


def _pymap3d(what: str):
    try:
        import pymap3d
    except ImportError:
        raise InputError(f"{what} needs pymap3d ({_INSTALL})") from None
    return pymap3d


def _frame(frame: Any, what: str) -> str:
    if not isinstance(frame, str) or frame.lower() not in _FRAMES:
        raise InputError(f"{what}: frame = {frame!r}; give \"enu\" (x east, y north, z up) or \"ned\" "
                         "(x north, y east, z down)")
    return frame.lower()


def _numbers(v: Any, what: str, units: str) -> np.ndarray:
    """A 1-D float array (scalars become length 1), every entry finite."""
    try:
        arr = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what}: expected numbers in {units}, got {type(v).__name__}") from None
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1 or arr.size == 0:
        raise InputError(f"{what}: expected a scalar or a 1-D array in {units}, got shape {arr.shape}")
    bad = np.flatnonzero(~np.isfinite(arr))
    if bad.size:
        raise InputError(f"{what}: entry {int(bad[0])} is {float(arr[bad[0]])!r}; values must be finite "
                         f"({units})")
    return arr


def _latitudes(lat: Any, what: str) -> np.ndarray:
    arr = _numbers(lat, what, "degrees")
    bad = np.flatnonzero(np.abs(arr) > 90.0)
    if bad.size:
        raise InputError(f"{what}: entry {int(bad[0])} is {float(arr[bad[0]])!r} degrees; latitudes lie in "
                         "[-90, 90] (latitude and longitude swapped?)")
    return arr


def _origin(origin: Any) -> tuple[float, float, float]:
    """Validate ``origin = (lat0, lon0, h0)``: degrees, degrees, m."""
    form = "give origin = (lat0, lon0, h0): degrees, degrees, m above the WGS-84 ellipsoid"
    try:
        arr = np.asarray(origin, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"origin = {origin!r}: {form}") from None
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise InputError(f"origin = {origin!r}: {form} (three finite numbers)")
    if abs(arr[0]) > 90.0:
        raise InputError(f"origin = {origin!r}: latitude {float(arr[0])!r} is outside [-90, 90]; {form}")
    return float(arr[0]), float(arr[1]), float(arr[2])


def _same_length(arrays: dict[str, np.ndarray]) -> int:
    n = max(a.size for a in arrays.values())
    for name, a in arrays.items():
        if a.size not in (1, n):
            sizes = {k: v.size for k, v in arrays.items()}
            raise InputError(f"{name}: {a.size} values, but the others have {n}; give one value per fix "
                             f"(or a scalar): sizes {sizes}")
    return n


def geodetic_to_local(lat: Any, lon: Any, height: Any, origin: Sequence[float], frame: str = "enu"
                      ) -> np.ndarray:
    r"""Geodetic WGS-84 coordinates to a local tangent frame about ``origin``.

    Parameters
    ----------
    lat, lon : float or array_like, shape (N,)
        Latitude in [-90, 90] and longitude, degrees (WGS-84).
    height : float or array_like, shape (N,)
        Height above the WGS-84 ellipsoid, m. Scalars are broadcast to N.
    origin : sequence of 3 float
        ``(lat0, lon0, h0)`` of the local frame's origin: degrees, degrees, m.
    frame : {"enu", "ned"}
        ``"enu"``: x east, y north, z up; ``"ned"``: x north, y east, z down.

    Returns
    -------
    numpy.ndarray, shape (N, 3)
        Local coordinates in m.

    Raises
    ------
    InputError
        For a non-finite value or a latitude outside [-90, 90] (naming its index), arrays
        of different lengths, a bad origin or frame, or pymap3d missing.

    Notes
    -----
    The point's ECEF position :math:`p` and the origin's :math:`p_0` are differenced and
    rotated into the tangent plane at :math:`(\varphi_0, \lambda_0)`:

    .. math::

        \begin{pmatrix} e \\ n \\ u \end{pmatrix} =
        \begin{pmatrix} -\sin\lambda_0 & \cos\lambda_0 & 0 \\
        -\sin\varphi_0\cos\lambda_0 & -\sin\varphi_0\sin\lambda_0 & \cos\varphi_0 \\
        \cos\varphi_0\cos\lambda_0 & \cos\varphi_0\sin\lambda_0 & \sin\varphi_0
        \end{pmatrix} (p - p_0),

    and NED is :math:`(n, e, -u)`. The frame is exact (no flat-Earth approximation): a
    point 10 km away lies about 8 m below the tangent plane (``z < 0`` in ENU).
    """
    frame = _frame(frame, "geodetic_to_local")
    lat0, lon0, h0 = _origin(origin)
    arrays = {"lat": _latitudes(lat, "lat"), "lon": _numbers(lon, "lon", "degrees"),
              "height": _numbers(height, "height", "m")}
    n = _same_length(arrays)
    la, lo, h = (np.broadcast_to(a, (n,)) for a in arrays.values())
    pm = _pymap3d("geodetic_to_local")
    conv = pm.geodetic2enu if frame == "enu" else pm.geodetic2ned
    a, b, c = conv(la, lo, h, lat0, lon0, h0, deg=True)
    return np.column_stack([np.asarray(a, float).reshape(n), np.asarray(b, float).reshape(n),
                            np.asarray(c, float).reshape(n)])


def local_to_geodetic(xyz: Any, origin: Sequence[float], frame: str = "enu"
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Local tangent-frame coordinates about ``origin`` back to geodetic WGS-84.

    Parameters
    ----------
    xyz : array_like, shape (N, 3) or (3,)
        Local coordinates in m, in ``frame``.
    origin : sequence of 3 float
        ``(lat0, lon0, h0)``: degrees, degrees, m above the ellipsoid.
    frame : {"enu", "ned"}
        As in :func:`geodetic_to_local`.

    Returns
    -------
    lat, lon, height : numpy.ndarray, shape (N,)
        Degrees, degrees, m above the WGS-84 ellipsoid.

    Notes
    -----
    The inverse of :func:`geodetic_to_local`: :math:`p = p_0 + R^T (e, n, u)^T` and ECEF
    to geodetic (pymap3d's closed form); a round trip is exact to well below 1 µm.
    """
    frame = _frame(frame, "local_to_geodetic")
    lat0, lon0, h0 = _origin(origin)
    try:
        arr = np.asarray(xyz, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"local_to_geodetic: xyz must be numbers in m, got {type(xyz).__name__}") from None
    if arr.ndim == 1 and arr.size == 3:
        arr = arr.reshape(1, 3)
    if arr.ndim != 2 or arr.shape[1] != 3 or arr.shape[0] == 0:
        raise InputError(f"local_to_geodetic: xyz has shape {arr.shape}; give (N, 3) coordinates in m")
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise InputError(f"local_to_geodetic: xyz[{i}, {j}] is {float(arr[i, j])!r}; coordinates must be "
                         "finite")
    pm = _pymap3d("local_to_geodetic")
    conv = pm.enu2geodetic if frame == "enu" else pm.ned2geodetic
    la, lo, h = conv(arr[:, 0], arr[:, 1], arr[:, 2], lat0, lon0, h0, deg=True)
    n = arr.shape[0]
    return (np.asarray(la, float).reshape(n), np.asarray(lo, float).reshape(n),
            np.asarray(h, float).reshape(n))


def normal_gravity(lat_deg: Any, h_m: Any = 0.0) -> Any:
    r"""Magnitude of WGS-84 normal gravity at a latitude and a height above the ellipsoid.

    Parameters
    ----------
    lat_deg : float or array_like
        Geodetic latitude in degrees, [-90, 90].
    h_m : float or array_like
        Height above the WGS-84 ellipsoid in m (default 0).

    Returns
    -------
    float or numpy.ndarray
        Normal gravity in m/s^2 (a float for scalar input).

    Raises
    ------
    InputError
        For a non-finite value or a latitude outside [-90, 90].

    Notes
    -----
    On the ellipsoid, Somigliana's closed formula (NIMA TR8350.2 eq. 4-1; Groves,
    *Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed.,
    eq. 2.134):

    .. math::

        \gamma_0(\varphi) = \gamma_e \frac{1 + k \sin^2\varphi}{\sqrt{1 - e^2 \sin^2\varphi}},
        \qquad k = \frac{b\,\gamma_p}{a\,\gamma_e} - 1,

    with :math:`\gamma_e = 9.7803253359`, :math:`\gamma_p = 9.8321849378` m/s^2. Above
    it, the second-order free-air correction (TR8350.2 eq. 4-3; Groves eq. 2.139):

    .. math::

        \gamma(\varphi, h) = \gamma_0(\varphi) \left[1 - \frac{2}{a}
        \left(1 + f + m - 2 f \sin^2\varphi\right) h + \frac{3}{a^2} h^2\right],
        \qquad m = \frac{\omega^2 a^2 b}{GM},

    a vertical gradient of about :math:`-3.086 \times 10^{-6}` s^-2; good to well below
    1e-6 m/s^2 for heights up to about 20 km.
    """
    scalar = np.ndim(lat_deg) == 0 and np.ndim(h_m) == 0
    lat = _latitudes(lat_deg, "normal_gravity: latitude")
    h = _numbers(h_m, "normal_gravity: height", "m")
    n = _same_length({"normal_gravity: latitude": lat, "normal_gravity: height": h})
    c = WGS84
    s2 = np.sin(np.radians(np.broadcast_to(lat, (n,)))) ** 2
    g0 = c["gamma_e"] * (1.0 + c["k"] * s2) / np.sqrt(1.0 - c["e2"] * s2)
    hh = np.broadcast_to(h, (n,))
    a = c["a"]
    g = g0 * (1.0 - 2.0 / a * (1.0 + c["f"] + c["m"] - 2.0 * c["f"] * s2) * hh + 3.0 / a**2 * hh**2)
    return float(g[0]) if scalar else g


def _sigma_rows(sigma: Any, n: int, frame: str) -> np.ndarray:
    """Per-fix, per-axis sigma (n, 3) from a scalar, (n,), (n, 2) horizontal/vertical or (n, 3)."""
    form = ("give a scalar, one value per fix (N,), (N, 2) columns (horizontal, vertical) or (N, 3) one "
            f"per axis of the {frame.upper()} frame, in m")
    try:
        arr = np.asarray(sigma, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"position_items: sigma = {sigma!r}: {form}") from None
    if arr.ndim == 0:
        arr = np.full((n, 3), float(arr))
    elif arr.ndim == 1 and arr.size == n:
        arr = np.repeat(arr[:, None], 3, axis=1)
    elif arr.shape == (n, 2):
        arr = np.column_stack([arr[:, 0], arr[:, 0], arr[:, 1]])  # x, y horizontal in ENU and NED
    elif arr.shape != (n, 3):
        raise InputError(f"position_items: sigma has shape {arr.shape} for {n} fixes: {form}")
    bad = np.argwhere(~(np.isfinite(arr) & (arr > 0)))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise InputError(f"position_items: sigma of fix {i}, axis {j} is {float(arr[i, j])!r}; sigmas are "
                         "finite positive numbers in m (omit sigma for hard fixes)")
    return arr


def position_items(t: Any, lat: Any, lon: Any, height: Any, origin: Sequence[float], frame: str = "enu",
                   sigma: Any = None, name: str = "gnss fixes",
                   axes: Sequence[str] = ("x", "y", "z")) -> Position:
    r"""GNSS fixes as one :class:`bvpnav.constraints.Position` item in a local frame.

    Parameters
    ----------
    t : array_like, shape (N,)
        Times of the fixes in s, on the IMU recording's clock.
    lat, lon, height : array_like, shape (N,)
        Degrees, degrees, m above the WGS-84 ellipsoid.
    origin : sequence of 3 float
        ``(lat0, lon0, h0)`` of the navigation frame's origin (the point ``r = 0``).
    frame : {"enu", "ned"}
        The navigation frame (:func:`geodetic_to_local`).
    sigma : float or array_like, optional
        Standard deviation of each fix in m: a scalar, one per fix (N,), (N, 2) columns
        (horizontal, vertical), or (N, 3) one per axis. ``None``: hard fixes (each fix is
        an exact position; rarely what GNSS deserves); otherwise soft.
    name : str
        The item's label in reports and messages.
    axes : sequence of 3 str
        The problem's axis names for the frame's x, y, z (default ``x``, ``y``, ``z``).

    Returns
    -------
    Position
        One item with N instants on the three axes.

    Notes
    -----
    Residual per fix k and axis a: :math:`\rho = r_a(t_k) - p_{k,a}` with :math:`p_k`
    the fix in the local frame (:func:`geodetic_to_local`); soft with weight
    :math:`1/\sigma_{k,a}^2`.
    """
    from .constraints import Position

    tt = _numbers(t, "position_items: t", "s")
    xyz = geodetic_to_local(lat, lon, height, origin, frame)
    if xyz.shape[0] != tt.size:
        raise InputError(f"position_items: {tt.size} times but {xyz.shape[0]} fixes; give one time per fix")
    axes = tuple(axes)
    if len(axes) != 3 or not all(isinstance(a, str) for a in axes):
        raise InputError(f"position_items: axes = {axes!r}; give three axis names for x, y, z of the frame")
    frame = _frame(frame, "position_items")
    if sigma is None:
        return Position(t=tt, value=xyz, axes=axes, name=name)
    return Position(t=tt, value=xyz, axes=axes, sigma=_sigma_rows(sigma, tt.size, frame), name=name)


def trajectory_to_geodetic(df: pd.DataFrame, origin: Sequence[float], frame: str = "enu",
                           axes: Sequence[str] = ("x", "y", "z")) -> pd.DataFrame:
    """A copy of a trajectory with its positions also in geodetic coordinates.

    Parameters
    ----------
    df : pandas.DataFrame
        A trajectory (e.g. :attr:`bvpnav.Solution.trajectory`) with local positions in m
        in the columns ``axes``; not modified.
    origin : sequence of 3 float
        ``(lat0, lon0, h0)`` of the local frame (what the fixes were converted about,
        e.g. a recording's ``meta["geodetic_origin"]``).
    frame : {"enu", "ned"}
        The local frame of the positions.
    axes : sequence of 3 str
        The columns holding the frame's x, y, z.

    Returns
    -------
    pandas.DataFrame
        A copy of ``df`` with columns ``lat``, ``lon`` (degrees) and ``height`` (m above
        the WGS-84 ellipsoid) added.

    Raises
    ------
    InputError
        For a missing column, a column ``lat``/``lon``/``height`` already present, or
        non-finite positions (naming the row).

    Notes
    -----
    Each row goes through :func:`local_to_geodetic`.
    """
    import pandas as pd

    if not isinstance(df, pd.DataFrame):
        raise InputError(f"trajectory_to_geodetic: expected a pandas DataFrame, got {type(df).__name__}")
    axes = tuple(axes)
    missing = [a for a in axes if a not in df.columns]
    if len(axes) != 3 or missing:
        raise InputError(f"trajectory_to_geodetic: axes = {axes!r}: need three position columns; missing "
                         f"{missing}; the frame has columns {list(df.columns)}")
    clash = [c for c in ("lat", "lon", "height") if c in df.columns]
    if clash:
        raise InputError(f"trajectory_to_geodetic: the frame already has columns {clash}; rename or drop "
                         "them first")
    if len(df) == 0:
        raise InputError("trajectory_to_geodetic: the trajectory has no rows")
    lat, lon, h = local_to_geodetic(df.loc[:, list(axes)].to_numpy(dtype=float), origin, frame)
    out = df.copy()
    out["lat"], out["lon"], out["height"] = lat, lon, h
    return out

