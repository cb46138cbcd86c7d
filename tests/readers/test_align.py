"""Information from another file on the recording's clock: explicit, exact, never silent."""

from __future__ import annotations

import numpy as np
import pytest

from bvpnav.constraints import Position, Velocity
from bvpnav.errors import InputError
from bvpnav.readers import Recording, align

T = np.arange(0.0, 10.01, 0.01)


def _imu(origin):
    return Recording(t=T, source="imu.csv", time_origin=origin, acc=np.zeros((T.size, 1)), axes=("x",))


def _info(origin, t=(0.5, 2.0, 7.25)):
    t = np.asarray(t, dtype=float)
    return Recording(t=t, source="fixes.nmea", time_origin=origin, items=(
        Position(t=t, value=np.column_stack([t, 2 * t]), sigma=np.full((t.size, 2), 0.5), axes=("x", "y"),
                 name="gnss"),
        Velocity(t=[t[0]], value=[[1.0, 2.0]], sigma=0.1, axes=("x", "y"), name="rmc")))


def test_iso_origins_with_zones_align_by_themselves_to_the_nanosecond():
    # the fixes' clock starts 1.25 s after the IMU's (one in UTC, one at +02:00)
    items, notes = align(_info("2026-05-01T10:00:01.250000000Z"), _imu("2026-05-01T12:00:00+02:00"))
    gnss = items[0]
    np.testing.assert_array_equal(gnss.t, np.array([0.5, 2.0, 7.25]) + 1.25)
    np.testing.assert_array_equal(gnss.value[:, 0], [0.5, 2.0, 7.25])  # values untouched
    assert items[1].t.tolist() == [1.75]
    assert any("+1.250000000 s" in n for n in notes), notes


def test_numeric_origins_need_same_clock_and_then_shift_exactly():
    info, imu = _info("1700000000500000000 ns"), _imu("1700000000000000000 ns")
    with pytest.raises(InputError, match=r"not known to be one.*--clock-offset SECONDS.*--same-clock"):
        align(info, imu)
    items, _ = align(info, imu, same_clock=True)
    np.testing.assert_array_equal(items[0].t, [1.0, 2.5, 7.75])


def test_a_given_offset_is_used_and_said():
    items, notes = align(_info(None), _imu(None), clock_offset=-0.25)
    np.testing.assert_array_equal(items[0].t, [0.25, 1.75, 7.0])
    assert notes == ["fixes.nmea: times shifted by the given clock offset -0.25 s"]
    with pytest.raises(InputError, match="either clock_offset .* or same_clock"):
        align(_info(None), _imu(None), clock_offset=1.0, same_clock=True)


def test_instants_outside_the_window_are_left_out_with_their_rows_and_counted():
    items, notes = align(_info("2026-05-01T10:00:05Z", t=(0.0, 4.0, 5.5, 8.0)), _imu("2026-05-01T10:00:00Z"))
    gnss = items[0]
    np.testing.assert_array_equal(gnss.t, [5.0, 9.0])
    np.testing.assert_array_equal(gnss.value, [[0.0, 0.0], [4.0, 8.0]])  # the rows of the kept fixes
    assert gnss.sigma.shape == (2, 2)
    assert any("2 of 5 instant(s) lie outside the recording's window [0, 10] s" in n for n in notes), notes
    with pytest.raises(InputError, match=r"no instant .* falls inside the recording's window"):
        align(_info("2026-05-01T11:00:00Z"), _imu("2026-05-01T10:00:00Z"))


def test_naive_timestamps_are_not_guessed_to_be_utc():
    with pytest.raises(InputError, match="not known to be one"):
        align(_info("2026-05-01T10:00:00"), _imu("2026-05-01T10:00:00Z"))
