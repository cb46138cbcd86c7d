r"""Attitude from gyro rates (scipy ``Rotation``), body-to-navigation convention.

Conventions used throughout bvpnav:

- the attitude ``C(t)`` rotates body-frame vectors into the navigation frame,
  ``v_nav = C v_body`` (``Rotation.apply``);
- gyro rates ``omega`` are the body's angular velocity relative to the navigation
  frame, expressed in body axes, in rad/s, so that :math:`\dot C = C [\omega\times]`
  (Earth rotation is neglected, as in the papers);
- quaternions are scipy's scalar-last ``(x, y, z, w)``.

Examples
--------
A body turning about its z axis at 0.5 rad/s for 1 s:

>>> import numpy as np
>>> from bvpnav.attitude import integrate_gyro
>>> t = np.linspace(0.0, 1.0, 11)
>>> C = integrate_gyro(t, np.tile([0.0, 0.0, 0.5], (11, 1)))
>>> print(np.round(C[-1].as_rotvec(), 6) + 0.0)
[0.  0.  0.5]
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from .errors import InputError
from .grid import TimeGrid

__all__ = ["integrate_gyro", "step_rotation_vectors", "cumulative_product", "body_rates"]


def _rates(gyro, n: int, what: str = "gyro") -> np.ndarray:
    try:
        w = np.asarray(gyro, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{what}: cannot be read as numbers; pass an (N, 3) array in rad/s") from None
    if w.shape != (n, 3):
        raise InputError(f"{what}: expected shape ({n}, 3) (one body rate per sample, rad/s), got {w.shape}")
    bad = np.argwhere(~np.isfinite(w))
    if bad.size:
        i, k = (int(v) for v in bad[0])
        raise InputError(f"{what}: sample {i}, axis {'xyz'[k]} is {float(w[i, k])!r}; rates must be "
                         "finite. Remove or repair that sample.")
    return w


def step_rotation_vectors(t, gyro) -> np.ndarray:
    r"""Body-frame rotation vector of every step ``t_k -> t_{k+1}``, rad.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s.
    gyro : array_like, shape (N, 3)
        Body angular rates, rad/s.

    Returns
    -------
    ndarray, shape (N - 1, 3)

    Notes
    -----
    With the rate linear over the step (the same assumption the FEM makes for the
    acceleration), the rotation vector to third order is

    .. math:: \phi_k = \frac{h_k}{2}(\omega_k + \omega_{k+1})
              + \frac{h_k^2}{12}\, \omega_k \times \omega_{k+1},

    the trapezoid rule plus the two-sample coning correction. It is exact for a
    constant rate axis.

    Examples
    --------
    >>> import numpy as np
    >>> from bvpnav.attitude import step_rotation_vectors
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> phi = step_rotation_vectors(t, np.tile([0.0, 0.0, 0.5], (11, 1)))
    >>> phi.shape, (np.round(phi[0], 6) + 0.0).tolist()  # one per step: 0.5 rad/s times 0.1 s
    ((10, 3), [0.0, 0.0, 0.05])
    """
    grid = TimeGrid(t)
    w = _rates(gyro, grid.n)
    h = grid.h[:, None]
    return 0.5 * h * (w[:-1] + w[1:]) + (h**2 / 12.0) * np.cross(w[:-1], w[1:])


def cumulative_product(steps: Rotation) -> Rotation:
    """Prefix products ``s_0, s_0 s_1, ..., s_0 s_1 ... s_{M-1}`` of a Rotation sequence.

    Uses ``log2(M)`` vectorised compositions (a parallel prefix scan) instead of a
    Python loop; composition is associative, so the result equals the sequential
    product up to rounding.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> from bvpnav.attitude import cumulative_product
    >>> steps = Rotation.from_rotvec(np.tile([0.0, 0.0, 0.05], (10, 1)))
    >>> C = cumulative_product(steps)
    >>> len(C), (np.round(C[-1].as_rotvec(), 6) + 0.0).tolist()
    (10, [0.0, 0.0, 0.5])
    """
    q = steps.as_quat()
    m = q.shape[0]
    off = 1
    while off < m:
        head = Rotation.from_quat(q[:-off])
        tail = Rotation.from_quat(q[off:])
        q = np.concatenate([q[:off], (head * tail).as_quat()])
        off *= 2
    return Rotation.from_quat(q)


def integrate_gyro(t, gyro, initial=None) -> Rotation:
    r"""Body-to-navigation attitude per sample from body angular rates.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s.
    gyro : array_like, shape (N, 3)
        Body angular rates relative to the navigation frame, rad/s.
    initial : scipy.spatial.transform.Rotation, optional
        Attitude at ``t[0]`` (body to navigation); default identity.

    Returns
    -------
    scipy.spatial.transform.Rotation of length N

    Notes
    -----
    :math:`C_{k+1} = C_k \exp([\phi_k \times])` with :math:`\phi_k` from
    :func:`step_rotation_vectors`. The global attitude error is :math:`O(h^2)` for a
    smooth rate; it is exact (to rounding) for a fixed rotation axis with a rate that
    is linear in time between samples.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> from bvpnav.attitude import integrate_gyro
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> start = Rotation.from_euler("z", 90, degrees=True)  # heading 90 degrees
    >>> C = integrate_gyro(t, np.tile([0.0, 0.0, 0.5], (11, 1)), initial=start)
    >>> len(C), round(float(C[-1].as_euler("zyx", degrees=True)[0]), 3)  # 90 + 28.648 degrees
    (11, 118.648)
    """
    phi = step_rotation_vectors(t, gyro)
    if initial is None:
        initial = Rotation.identity()
    if not isinstance(initial, Rotation) or not initial.single:
        raise InputError("initial: give one scipy Rotation (the body-to-navigation attitude at t[0])")
    if phi.shape[0] == 0:
        return Rotation.from_quat(initial.as_quat()[None, :])
    acc = cumulative_product(Rotation.from_rotvec(phi))
    rest = initial * acc
    return Rotation.from_quat(np.concatenate([initial.as_quat()[None, :], rest.as_quat()]))


def body_rates(t, attitude: Rotation) -> np.ndarray:
    r"""Body angular rates (rad/s) implied by an attitude sequence, by central differences.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s.
    attitude : Rotation of length N
        Body-to-navigation attitude.

    Returns
    -------
    ndarray, shape (N, 3)

    Notes
    -----
    :math:`\omega_k \approx \log(C_{k-1}^T C_{k+1}) / (t_{k+1} - t_{k-1})`
    (one-sided at the ends); second order in the step for uniform sampling.
    Meant for checks and for attitude histories given only as samples.

    Examples
    --------
    The rates back from an attitude history:

    >>> import numpy as np
    >>> from bvpnav.attitude import body_rates, integrate_gyro
    >>> t = np.linspace(0.0, 1.0, 11)
    >>> C = integrate_gyro(t, np.tile([0.1, 0.0, 0.5], (11, 1)))
    >>> (np.round(body_rates(t, C)[5], 6) + 0.0).tolist()
    [0.1, 0.0, 0.5]
    """
    grid = TimeGrid(t)
    n = grid.n
    if not isinstance(attitude, Rotation) or attitude.single or len(attitude) != n:
        raise InputError(f"attitude: expected a Rotation of length {n}")
    tt = grid.t
    lo = np.concatenate([[0], np.arange(n - 2), [n - 2]])
    hi = np.concatenate([[1], np.arange(2, n), [n - 1]])
    rel = attitude[lo].inv() * attitude[hi]
    return rel.as_rotvec() / (tt[hi] - tt[lo])[:, None]
