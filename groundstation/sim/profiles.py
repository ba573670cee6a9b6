"""Truth profiles: exact attitude, body rate and linear acceleration at any instant, from a seed.

A profile is six smooth channels of time: the ZYX Euler angles (roll φ, pitch θ, yaw ψ, rad) and
the NED position (north, east, down, m). Each channel is a sum of components that give the value
and its first and second time derivatives in closed form, so everything derived is exact, not a
finite difference:

- attitude ``q = qz(ψ) ⊗ qy(θ) ⊗ qx(φ)`` rotates body (FRD) vectors into NED;
- body rate from the Euler rates (ZYX kinematics)::

      p = φ' - ψ' sin θ
      q = θ' cos φ + ψ' sin φ cos θ
      r = -θ' sin φ + ψ' cos φ cos θ

- linear acceleration, velocity and position in NED are the position channels' derivatives.

Every profile starts with ``REST_S`` seconds level, heading north and at rest: the simulated
firmware calibrates its gyro there, as a real board does at power-up. Profiles are defined for any
duration; evaluation is vectorised over a block of times, so hours of flight cost seconds.

Profiles (``PROFILES``): ``static`` (at rest), ``hover`` (small attitude wander, motor vibration),
``flight`` (pitch/roll manoeuvres up to ±30°, yaw turns, climbs), ``aggressive`` (10 min of
continuous manoeuvring without rest: roll and pitch swinging up to about ±50°, turns at up to 300 °/s,
accelerations up to about 8 m/s²), ``slide`` (horizontal translation
at zero attitude, accelerations up to ±3 m/s², the paper's sliding test), ``fast`` (flips at
550-900 °/s, beyond a ±500 °/s gyro range), ``car`` (driving at up to
15 m/s with speed changes and turns, yaw along the velocity: seed 001's test) and ``turntable`` (seed
003's three-axis turntable: ±25° sines on pitch, roll and yaw with periods 47 s, 35 s and 15 s after
60 s at rest, position fixed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from groundstation import quaternion as quat
from groundstation.sim.seeds import stream
from groundstation.sim.settings import DEFAULT_DURATION_S, PROFILES
from groundstation.units import STANDARD_GRAVITY_M_S2

REST_S = 2.0
GRAVITY_NED_M_S2 = np.array([0.0, 0.0, STANDARD_GRAVITY_M_S2])
# Largest |d²s/du²| of the quintic smoothstep s(u) = 10u³ - 15u⁴ + 6u⁵ (at u = (3 - √3)/6).
_SMOOTHSTEP_PEAK_ACCEL = 10.0 / math.sqrt(3.0)
# Largest ds/du of the same smoothstep (at u = 1/2).
_SMOOTHSTEP_PEAK_RATE = 1.875



class Moves:
    """Smooth moves between held values: from ``values[i]`` at ``times_s[i]`` to ``values[i+1]`` at
    ``times_s[i+1]`` along the quintic smoothstep (zero rate and acceleration at every knot).
    Before the first knot and after the last the value holds."""

    def __init__(self, times_s, values):
        self.times_s = np.asarray(times_s, dtype=float)
        self.values = np.asarray(values, dtype=float)
        if len(self.times_s) < 2 or np.any(np.diff(self.times_s) <= 0):
            raise ValueError("Moves needs at least two strictly increasing knot times")

    def __call__(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        i = np.clip(np.searchsorted(self.times_s, t_s, side="right") - 1, 0, len(self.times_s) - 2)
        span = self.times_s[i + 1] - self.times_s[i]
        delta = self.values[i + 1] - self.values[i]
        u = np.clip((t_s - self.times_s[i]) / span, 0.0, 1.0)
        s = u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
        ds = 30.0 * u * u * (1.0 - u) ** 2
        d2s = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u)
        return self.values[i] + delta * s, delta * ds / span, delta * d2s / span**2


class Sines:
    """``Σ amplitude · sin(2π f t + phase)``, faded in over ``ramp_s`` from ``start_s`` (so the
    profile's initial rest stays exactly at rest)."""

    def __init__(self, amplitudes, freqs_hz, phases_rad, start_s: float = REST_S, ramp_s: float = 2.0):
        self.amplitudes = np.asarray(amplitudes, dtype=float)
        self.omegas = 2.0 * math.pi * np.asarray(freqs_hz, dtype=float)
        self.phases = np.asarray(phases_rad, dtype=float)
        self.fade = Moves([start_s, start_s + ramp_s], [0.0, 1.0])

    def __call__(self, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        angle = np.multiply.outer(t_s, self.omegas) + self.phases
        sin, cos = np.sin(angle), np.cos(angle)
        x = sin @ self.amplitudes
        dx = cos @ (self.amplitudes * self.omegas)
        d2x = -(sin @ (self.amplitudes * self.omegas**2))
        e, de, d2e = self.fade(t_s)
        # Product rule: (e x)' = e' x + e x'; (e x)'' = e'' x + 2 e' x' + e x''.
        return e * x, de * x + e * dx, d2e * x + 2.0 * de * dx + e * d2x


@dataclass(frozen=True)
class Truth:
    """The true state at ``n`` instants. Arrays are float64; units in the names.

    ``q_body_to_ned`` (n, 4), w first, rotates body FRD vectors into NED; ``rate_body_rad_s`` (n, 3)
    is the body angular rate; ``acc_ned_m_s2``, ``vel_ned_m_s``, ``pos_ned_m`` (n, 3) the linear
    motion (acceleration without gravity).
    """

    t_s: np.ndarray
    q_body_to_ned: np.ndarray
    rate_body_rad_s: np.ndarray
    acc_ned_m_s2: np.ndarray
    vel_ned_m_s: np.ndarray
    pos_ned_m: np.ndarray

    def specific_force_body_m_s2(self) -> np.ndarray:
        """What an ideal accelerometer on the body axes reads (n, 3): ``R^T (a - g)``; 1 g up at rest."""
        return quat.rotate(quat.conjugate(self.q_body_to_ned), self.acc_ned_m_s2 - GRAVITY_NED_M_S2)


class Profile:
    """A named, seeded truth trajectory. ``truth(t_s)`` evaluates it at any times (s since boot)."""

    def __init__(self, name: str, duration_s: float, seed: int, channels: dict[str, list]):
        self.name = name
        self.duration_s = duration_s
        self.seed = seed
        self._channels = channels

    def _channel(self, name: str, t_s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        total = [np.zeros_like(t_s), np.zeros_like(t_s), np.zeros_like(t_s)]
        for component in self._channels.get(name, ()):
            for k, part in enumerate(component(t_s)):
                total[k] = total[k] + part
        return total[0], total[1], total[2]

    def truth(self, t_s) -> Truth:
        t_s = np.atleast_1d(np.asarray(t_s, dtype=float))
        roll, droll, _ = self._channel("roll", t_s)
        pitch, dpitch, _ = self._channel("pitch", t_s)
        yaw, dyaw, _ = self._channel("yaw", t_s)
        sr, cr, sp, cp = np.sin(roll), np.cos(roll), np.sin(pitch), np.cos(pitch)
        rate = np.stack(
            [droll - dyaw * sp, dpitch * cr + dyaw * sr * cp, -dpitch * sr + dyaw * cr * cp], axis=-1
        )
        pos, vel, acc = zip(*(self._channel(axis, t_s) for axis in ("north", "east", "down")))
        return Truth(
            t_s=t_s,
            q_body_to_ned=quat.from_euler_zyx(yaw, pitch, roll),
            rate_body_rad_s=rate,
            acc_ned_m_s2=np.stack(acc, axis=-1),
            vel_ned_m_s=np.stack(vel, axis=-1),
            pos_ned_m=np.stack(pos, axis=-1),
        )



def _moves(rng, duration_s, hold_s, step) -> Moves:
    """Knots from REST_S to past ``duration_s``: hold for ``rng.uniform(*hold_s)``, then
    ``step(rng, value) -> (new value, move time s)``."""
    times, values = [0.0, REST_S], [0.0, 0.0]
    while times[-1] <= duration_s:
        times.append(times[-1] + rng.uniform(*hold_s))
        values.append(values[-1])
        value, move_s = step(rng, values[-1])
        times.append(times[-1] + move_s)
        values.append(value)
    return Moves(times, values)


def _move_time_s(delta: float, peak_accel: float) -> float:
    """Duration of a smoothstep move of size ``delta`` whose peak second derivative is ``peak_accel``."""
    return max(math.sqrt(_SMOOTHSTEP_PEAK_ACCEL * abs(delta) / peak_accel), 0.2)


def _random_sines(rng, amplitude, freqs_hz) -> Sines:
    n = len(freqs_hz)
    return Sines(amplitude * rng.uniform(0.5, 1.0, n) / math.sqrt(n), freqs_hz, rng.uniform(0, 2 * math.pi, n))


def _static(rng, duration_s):
    return {}


def _hover(rng, duration_s):
    deg = math.radians
    wander_hz = rng.uniform(0.05, 0.5, 3)
    # Motor vibration: ~150 Hz and its harmonic in the specific force (m/s² amplitude), a trace in the
    # attitude at the frame's bending mode (~35 Hz). Sampled at 100 Hz it aliases, as on real boards.
    vib_hz = rng.uniform(140.0, 160.0) * np.array([1.0, 2.0])
    vib_m_s2 = np.array([1.0, 0.4])

    def vibration(axis_gain):
        return Sines(axis_gain * vib_m_s2 / (2 * math.pi * vib_hz) ** 2, vib_hz, rng.uniform(0, 2 * math.pi, 2))

    climb = Moves([REST_S, REST_S + 3.0], [0.0, -1.5])  # take off to 1.5 m, then hold
    return {
        "roll": [_random_sines(rng, deg(2.0), wander_hz), _random_sines(rng, deg(0.03), [rng.uniform(30, 40)])],
        "pitch": [_random_sines(rng, deg(2.0), rng.uniform(0.05, 0.5, 3)), _random_sines(rng, deg(0.03), [rng.uniform(30, 40)])],
        "yaw": [_random_sines(rng, deg(5.0), rng.uniform(0.02, 0.1, 2))],
        "north": [_random_sines(rng, 0.3, rng.uniform(0.05, 0.3, 2)), vibration(0.5)],
        "east": [_random_sines(rng, 0.3, rng.uniform(0.05, 0.3, 2)), vibration(0.5)],
        "down": [climb, _random_sines(rng, 0.1, rng.uniform(0.05, 0.3, 2)), vibration(1.0)],
    }


def _flight(rng, duration_s):
    deg = math.radians

    def tilt(rng, value):  # a new attitude up to ±30°, or back to level half the time
        target = 0.0 if value != 0.0 and rng.random() < 0.5 else deg(rng.uniform(-30.0, 30.0))
        return target, rng.uniform(0.5, 2.0)

    def turn(rng, value):
        angle = deg(rng.uniform(30.0, 180.0)) * rng.choice([-1.0, 1.0])
        return value + angle, rng.uniform(2.0, 5.0)

    def altitude(rng, value):  # between 2 and 10 m up (down is negative)
        target = -rng.uniform(2.0, 10.0)
        return target, _move_time_s(target - value, rng.uniform(0.5, 1.5))

    def horizontal(rng, value):
        target = rng.uniform(-30.0, 30.0)
        return target, _move_time_s(target - value, rng.uniform(0.5, 2.0))

    return {
        "roll": [_moves(rng, duration_s, (0.5, 3.0), tilt)],
        "pitch": [_moves(rng, duration_s, (0.5, 3.0), tilt)],
        "yaw": [_moves(rng, duration_s, (2.0, 8.0), turn)],
        "north": [_moves(rng, duration_s, (1.0, 4.0), horizontal)],
        "east": [_moves(rng, duration_s, (1.0, 4.0), horizontal)],
        "down": [_moves(rng, duration_s, (2.0, 6.0), altitude)],
    }


def _aggressive(rng, duration_s):
    """Aggressive flight without a moment's rest: roll and pitch always swinging (three sines each,
    up to about ±50°), yaw turning (90-360° in 2-5 s, then the next after at most 0.5 s), the
    position always swinging (accelerations up to about 8 m/s²)."""
    deg = math.radians

    def turn(rng, value):
        return value + deg(rng.uniform(90.0, 360.0)) * rng.choice([-1.0, 1.0]), rng.uniform(2.0, 5.0)

    return {
        "roll": [_random_sines(rng, deg(35.0), rng.uniform(0.05, 0.6, 3))],
        "pitch": [_random_sines(rng, deg(35.0), rng.uniform(0.05, 0.6, 3))],
        "yaw": [_moves(rng, duration_s, (0.1, 0.5), turn)],
        "north": [_random_sines(rng, 2.5, rng.uniform(0.1, 0.3, 3))],
        "east": [_random_sines(rng, 2.5, rng.uniform(0.1, 0.3, 3))],
        "down": [_random_sines(rng, 1.0, rng.uniform(0.1, 0.3, 2))],
    }


def _slide(rng, duration_s):
    def slide(rng, value):  # back and forth along north, peak acceleration 1.5-3 m/s²
        target = -np.sign(value or 1.0) * rng.uniform(0.5, 3.0)
        return target, _move_time_s(target - value, rng.uniform(1.5, 3.0))

    return {"north": [_moves(rng, duration_s, (0.5, 2.0), slide)]}


def _fast(rng, duration_s):
    def flip(rng, value):  # to a large angle and back to level at 550-900 °/s peak
        target = 0.0 if value != 0.0 else math.radians(rng.uniform(45.0, 80.0)) * rng.choice([-1.0, 1.0])
        return target, _SMOOTHSTEP_PEAK_RATE * abs(target - value) / math.radians(rng.uniform(550.0, 900.0))

    return {
        "roll": [_moves(rng, duration_s, (1.0, 3.0), flip)],
        "pitch": [_moves(rng, duration_s, (1.5, 4.0), flip)],
    }


class _Drive:
    """Where a car is: the integral of its speed along its nose, ``v (cos θ cos ψ, cos θ sin ψ, -sin θ)``
    with θ the road grade (the pitch channel) and ψ the heading (the yaw channel), so it always drives
    where it points. Velocity and acceleration are closed form (product rule); the position is summed by
    8-point Gauss-Legendre over pieces cut at every knot of the speed and yaw moves, where the integrand
    is analytic, so it is exact to rounding."""

    def __init__(self, speed: Moves, pitch: Sines, yaw: Moves, duration_s: float, piece_s: float = 0.05):
        self.speed, self.pitch, self.yaw = speed, pitch, yaw
        grid = np.arange(0.0, duration_s + 2.0 * piece_s, piece_s)
        self._edges = np.unique(np.concatenate([grid, speed.times_s, yaw.times_s]))
        self._nodes, self._weights = np.polynomial.legendre.leggauss(8)
        pieces = self._integral(self._edges[:-1], self._edges[1:])
        self._at_edges = np.vstack([np.zeros((1, 3)), np.cumsum(pieces, axis=0)])

    def _motion(self, t_s):
        """NED velocity and acceleration (..., 3) at ``t_s``."""
        v, dv, _ = self.speed(t_s)
        theta, dtheta, _ = self.pitch(t_s)
        psi, dpsi, _ = self.yaw(t_s)
        st, ct, sp, cp = np.sin(theta), np.cos(theta), np.sin(psi), np.cos(psi)
        nose = np.stack([ct * cp, ct * sp, -st], axis=-1)
        turn = np.stack([-st * dtheta * cp - ct * sp * dpsi, -st * dtheta * sp + ct * cp * dpsi, -ct * dtheta], axis=-1)
        return v[..., None] * nose, dv[..., None] * nose + v[..., None] * turn

    def _integral(self, a_s, b_s):
        half = (b_s - a_s)[:, None] / 2.0
        vel, _ = self._motion((a_s[:, None] + b_s[:, None]) / 2.0 + half * self._nodes)
        return half * np.einsum("k,nkj->nj", self._weights, vel)

    def axis(self, j: int):
        """The component of NED axis ``j`` (0 north, 1 east, 2 down) for the profile's channels."""

        def component(t_s):
            i = np.clip(np.searchsorted(self._edges, t_s, side="right") - 1, 0, len(self._edges) - 1)
            pos = self._at_edges[i] + self._integral(self._edges[i], t_s)
            vel, acc = self._motion(t_s)
            return pos[:, j], vel[:, j], acc[:, j]

        return component


def _car(rng, duration_s):
    """Seed 001's test car (up to 15 m/s): speed up, cruise, brake, turn at the lower speed, again.

    Longitudinal and peak lateral accelerations 0.8-1.5 m/s² (the paper's uncompensated tilt error of
    up to ~7° is ~1.2 m/s²); body roll outwards in turns at 0.5°/(m/s²), plus road camber; pitch is
    the road grade (±2°), which the car climbs.
    """
    deg = math.radians
    t, v, psi = REST_S, 0.0, 0.0
    speed_t, speed_v = [0.0, t], [0.0, 0.0]
    yaw_t, yaw_v, roll_t, roll_v = [0.0, t], [0.0, 0.0], [0.0, t], [0.0, 0.0]
    while t <= duration_s:
        for target, hold_s in ((rng.uniform(8.0, 15.0), rng.uniform(3.0, 8.0)), (rng.uniform(4.0, 8.0), 0.0)):
            t += _move_time_s(target - v, rng.uniform(0.8, 1.5)) + hold_s  # speed up and cruise; brake
            v = target
            speed_t.append(t)
            speed_v.append(v)
        turn = deg(rng.uniform(30.0, 120.0)) * rng.choice([-1.0, 1.0])
        lateral_m_s2 = rng.uniform(0.8, 1.5)  # peak v ψ' of the smoothstep turn
        span_s = _SMOOTHSTEP_PEAK_RATE * abs(turn) * v / lateral_m_s2
        yaw_t += [t, t + span_s]
        yaw_v += [psi, psi + turn]
        psi += turn
        roll_t += [t, t + span_s / 2.0, t + span_s]
        roll_v += [0.0, -math.copysign(deg(0.5) * lateral_m_s2, turn), 0.0]
        t += span_s
        speed_t.append(t)
        speed_v.append(v)
    speed, yaw = Moves(speed_t, speed_v), Moves(yaw_t, yaw_v)
    grade = _random_sines(rng, deg(2.0), rng.uniform(0.01, 0.05, 2))
    drive = _Drive(speed, grade, yaw, duration_s)
    return {
        "roll": [Moves(roll_t, roll_v), _random_sines(rng, deg(1.0), rng.uniform(0.01, 0.05, 2))],
        "pitch": [grade],
        "yaw": [yaw],
        "north": [drive.axis(0)],
        "east": [drive.axis(1)],
        "down": [drive.axis(2)],
    }


# Seed 003's turntable: the rest during which the paper took its field and gravity references.
TURNTABLE_REST_S = 60.0


def _turntable(rng, duration_s):
    """±25° on each axis, periods 47 s (pitch), 35 s (roll), 15 s (yaw); 765 s = the rest + 15 pitch periods."""

    def sine(period_s):
        return Sines([math.radians(25.0)], [1.0 / period_s], [0.0], start_s=TURNTABLE_REST_S)

    return {"pitch": [sine(47.0)], "roll": [sine(35.0)], "yaw": [sine(15.0)]}


_BUILDERS = {"static": _static, "hover": _hover, "flight": _flight, "aggressive": _aggressive, "slide": _slide, "fast": _fast, "car": _car, "turntable": _turntable}


def make_profile(name: str, duration_s: float | None = None, seed: int = 0) -> Profile:
    """The profile ``name`` (one of ``PROFILES``), deterministic from ``seed``."""
    if name not in _BUILDERS:
        raise ValueError(f"unknown profile {name!r}; choose one of {', '.join(PROFILES)}")
    if duration_s is None:
        duration_s = DEFAULT_DURATION_S[name]
    if not duration_s > 0:
        raise ValueError(f"duration must be positive, not {duration_s!r} s")
    rng = stream(seed, f"profile {name}")
    return Profile(name, float(duration_s), seed, _BUILDERS[name](rng, float(duration_s)))
