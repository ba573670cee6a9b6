"""Pressure altitude and the local NED frame against independent figures."""

import numpy as np

from groundstation import geodesy


def test_isa_pressure_at_known_heights_and_its_inverse():
    # ICAO standard atmosphere tables: 1000 m -> 89 874.6 Pa, 3000 m -> 70 108.5 Pa (from 101 325 Pa, 15 °C).
    assert np.allclose(geodesy.pressure_pa([1000.0, 3000.0], 101_325.0), [89_874.6, 70_108.5], rtol=2e-4)
    heights = np.linspace(-100.0, 4000.0, 50)
    assert np.allclose(geodesy.pressure_altitude_m(geodesy.pressure_pa(heights, 100_000.0, 5.0), 100_000.0, 5.0), heights, atol=1e-6)
    # Near the ground one hectopascal is about 8.3 m.
    assert abs(geodesy.pressure_altitude_m(101_225.0, 101_325.0) - 8.3) < 0.1


def test_local_frame_distances_and_round_trip():
    origin = (52.5, 13.4, 40.0)
    one_degree_north = geodesy.ned_from_geodetic(53.5, 13.4, 40.0, origin)
    assert np.allclose(one_degree_north, [111_195.0, 0.0, 0.0], atol=1.0)  # 2πR/360 with R = 6371 km
    east = geodesy.ned_from_geodetic(52.5, 13.41, 45.0, origin)
    assert np.isclose(east[1], 1111.95 * np.cos(np.radians(52.5)), rtol=1e-4) and east[2] == -5.0
    points = np.random.default_rng(0).normal(0.0, 500.0, (100, 3))
    back = geodesy.ned_from_geodetic(*geodesy.geodetic_from_ned(points, origin), origin)
    assert np.allclose(back, points, atol=1e-6)
