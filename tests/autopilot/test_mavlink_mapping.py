"""Each mapped message against its definition's units, computed here by hand from the fields we encoded
(pymavlink's encoder makes the bytes; the decoder reads them back)."""

import math

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from groundstation import quaternion
from groundstation.autopilot import records as rec
from groundstation.autopilot.decoder import MavlinkDecoder

from mavlink_helpers import Sender, ardupilot_heartbeat


def decode(*packets):
    decoder = MavlinkDecoder()
    return decoder.feed(b"".join(packets)), decoder


def of(records, kind):
    return [r for r in records if isinstance(r, kind)]


def test_ardupilot_raw_imu_is_scaled_milli_units_on_the_body_axes():
    ap = Sender()
    records, _ = decode(ardupilot_heartbeat(ap), ap.raw_imu(123_456_789, 12, -500, -981, 100, -2000, 31, 200, -50, 400, 0, 3512))
    (imu,) = of(records, rec.ImuSample)
    assert imu.time_us == 123_456_789 and imu.source == "RAW_IMU"
    assert imu.acc_g == pytest.approx((0.012, -0.5, -0.981))
    assert imu.gyr_rad_s == pytest.approx((0.1, -2.0, 0.031))
    assert imu.temperature_c == pytest.approx(35.12)
    (mag,) = of(records, rec.MagReading)
    assert mag.mag_uT == pytest.approx((20.0, -5.0, 40.0))  # mgauss * 0.1


def test_raw_imu_of_an_unknown_or_other_autopilot_is_kept_generic_not_guessed():
    px4 = Sender()
    heartbeat = px4.heartbeat(mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_PX4, 0, 0, 0)
    for packets in ([px4.raw_imu(1, 2, 3, 4, 5, 6, 7, 8, 9, 10)], [heartbeat, px4.raw_imu(1, 2, 3, 4, 5, 6, 7, 8, 9, 10)]):
        records, _ = decode(*packets)
        assert not of(records, rec.ImuSample)
        (generic,) = [r for r in of(records, rec.GenericMessage) if r.msg_type == "RAW_IMU"]
        assert generic.fields["xacc"] == 2.0 and generic.units["xacc"] == "mG"


def test_scaled_imu2_from_any_autopilot_and_zero_temperature_means_none():
    s = Sender(7, 1)
    records, _ = decode(s.scaled_imu2(5000, 1000, 0, -1000, 0, 0, 1571, 0, 0, 0, 0))
    (imu,) = of(records, rec.ImuSample)
    assert (imu.system, imu.time_us) == (7, 5_000_000)
    assert imu.acc_g == pytest.approx((1.0, 0.0, -1.0)) and imu.gyr_rad_s[2] == pytest.approx(1.571)
    assert math.isnan(imu.temperature_c)


def test_highres_imu_si_units_to_g_and_microtesla_and_its_pressure():
    s = Sender()
    records, _ = decode(s.highres_imu(99, 0.0, 0.0, -9.80665, 0.1, 0.2, 0.3, 0.2, 0.0, 0.4, 1013.25, 0.0, 0.0, 21.5, 0xFFFF))
    (imu,) = of(records, rec.ImuSample)
    assert imu.acc_g == pytest.approx((0.0, 0.0, -1.0)) and imu.gyr_rad_s == pytest.approx((0.1, 0.2, 0.3))
    (mag,) = of(records, rec.MagReading)
    assert mag.mag_uT == pytest.approx((20.0, 0.0, 40.0))
    (baro,) = of(records, rec.BaroReading)
    assert baro.pressure_hpa == pytest.approx(1013.25) and baro.temperature_c == pytest.approx(21.5)


def test_attitude_euler_and_quaternion_give_the_same_body_to_ned_rotation():
    yaw, pitch, roll = 2.0, 0.3, -0.6
    s = Sender()
    # Body -> NED of ZYX (yaw, pitch, roll) composed by hand from the three axis rotations.
    def axis(angle, k):
        q = np.zeros(4)
        q[0], q[k] = math.cos(angle / 2), math.sin(angle / 2)
        return q
    expected = quaternion.multiply(quaternion.multiply(axis(yaw, 3), axis(pitch, 2)), axis(roll, 1))
    records, _ = decode(s.attitude(1000, roll, pitch, yaw, 0, 0, 0), s.attitude_quaternion(1000, *expected, 0, 0, 0))
    euler, quat = of(records, rec.OnboardAttitude)
    assert euler.time_us == 1_000_000 and euler.source == "ATTITUDE"
    assert np.allclose(euler.q, expected, atol=1e-6) or np.allclose(euler.q, -expected, atol=1e-6)
    assert np.allclose(quat.q, expected, atol=1e-6)
    # Nose up 0.3 rad: the body x axis points up out of the horizontal plane (NED z negative).
    nose = quaternion.rotate(np.array(euler.q), np.array([1.0, 0, 0]))
    assert nose[2] == pytest.approx(-math.sin(pitch))


def test_gps_raw_int_units_and_velocity_from_speed_and_course():
    s = Sender()
    records, _ = decode(s.gps_raw_int(7_000_000, 3, 525_000_000, 134_000_000, 40_500, 100, 150, 500, 9000, 12))
    (fix,) = of(records, rec.GpsReading)
    assert (fix.lat_deg, fix.lon_deg, fix.alt_m) == pytest.approx((52.5, 13.4, 40.5))
    assert (fix.vel_n_m_s, fix.vel_e_m_s) == pytest.approx((0.0, 5.0), abs=1e-9)  # 5 m/s due east
    assert math.isnan(fix.vel_d_m_s) and fix.fix_type == 3 and fix.satellites == 12
    unknown, _ = decode(s.gps_raw_int(1, 1, 0, 0, 0, 0, 0, 65535, 65535, 255))
    assert math.isnan(of(unknown, rec.GpsReading)[0].vel_n_m_s) and of(unknown, rec.GpsReading)[0].satellites == -1


def test_link_health_battery_mode_and_armed():
    ap, radio = Sender(), Sender(51, 68)
    records, _ = decode(ardupilot_heartbeat(ap), ap.sys_status(0, 0, 0, 0, 12_600, 1530, 76, 250, 3, 0, 0, 0, 0),
                        radio.radio_status(180, 170, 90, 40, 45, 7, 2), ap.scaled_pressure(10, 1001.5, 0.0, 0))
    (status,) = of(records, rec.VehicleStatus)
    assert status.armed and status.mode == "LOITER" and status.autopilot == mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA
    (battery,) = of(records, rec.Battery)
    assert (battery.voltage_v, battery.current_a, battery.remaining_pct, battery.drop_rate_comm_pct) == pytest.approx((12.6, 15.3, 76, 2.5))
    (link,) = of(records, rec.LinkHealth)
    assert (link.system, link.rssi, link.remote_rssi, link.noise, link.remote_noise, link.rx_errors) == (51, 180, 170, 40, 45, 7)
    (baro,) = of(records, rec.BaroReading)
    assert baro.pressure_hpa == pytest.approx(1001.5) and math.isnan(baro.temperature_c)
    unknown, _ = decode(ap.sys_status(0, 0, 0, 0, 65535, -1, -1, 0, 0, 0, 0, 0, 0))
    assert all(math.isnan(v) for v in of(unknown, rec.Battery)[0][3:6])


def test_every_other_message_is_a_generic_row_with_units_and_flattened_arrays():
    s = Sender()
    records, _ = decode(s.vfr_hud(12.5, 13.0, 270, 55, 100.25, -1.5), s.servo_output_raw(5, 0, *range(1000, 1008)))
    hud, servo = of(records, rec.GenericMessage)
    assert hud.msg_type == "VFR_HUD" and hud.fields["airspeed"] == 12.5 and hud.units["airspeed"] == "m/s"
    assert hud.time_us is None and servo.time_us == 5
    assert servo.fields["servo3_raw"] == 1002.0 and servo.units["servo3_raw"] == "us"
