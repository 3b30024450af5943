#!/usr/bin/env python3
"""Damping of a TSID frame task's loop (one axis) against the lags of the velocity it reads.

The task asks `a = -K_p x - K_d v_meas` of a double integrator. The realised acceleration lags the command
by the motor's first-order torque lag (30 Hz, `sim.actuation.default.torque_bandwidth`) and a pure delay
of 2 ms (command and sensor delays, the 500 Hz zero-order hold; first-order Padé). The measured velocity is
either the encoders' low-passed difference (first-order, 10 Hz: `sim.sensors.encoder.velocity_cutoff`) or
the estimation layer's critically damped alpha-beta filter at f Hz, whose velocity is `w^2/(s+w)^2` of the
true one (docs/wbc.md, "Joint velocities"). Prints the damping ratio and frequency of the least damped
closed-loop pole. Pure Python (no numpy): `python3 tools/wbc/velocity_lag_poles.py`.
"""
import math


def mul(a, b):
    r = [0.0] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            r[i + j] += x * y
    return r


def add(a, b):
    n = max(len(a), len(b))
    a = [0.0] * (n - len(a)) + a
    b = [0.0] * (n - len(b)) + b
    return [x + y for x, y in zip(a, b)]


def roots(p):
    """Durand-Kerner iteration on the monic polynomial (highest degree first)."""
    p = [c / p[0] for c in p]
    n = len(p) - 1
    z = [(0.4 + 0.9j) ** k for k in range(n)]
    for _ in range(3000):
        new = []
        for i in range(n):
            num = sum(c * z[i] ** (n - k) for k, c in enumerate(p))
            den = 1.0
            for j in range(n):
                if j != i:
                    den *= z[i] - z[j]
            new.append(z[i] - num / den)
        z = new
    return z


def least_damped(char):
    r = [x for x in roots(char) if abs(x) < 1e5]
    zeta, w = min((-x.real / abs(x), abs(x)) for x in r)
    return zeta, w


def loop(kp, kd, velocity_filter, torque_lag=1 / (2 * math.pi * 30), delay=0.002):
    """Characteristic polynomial: s^2 (ta s+1)(d/2 s+1) D(s) + (1 - d/2 s)(kp D(s) + kd s N(s)), the
    velocity filter N/D."""
    num, den = velocity_filter
    plant = mul(mul([1.0, 0.0, 0.0], [torque_lag, 1.0]), [delay / 2, 1.0])
    control = add([kp * c for c in den], mul([kd, 0.0], num))
    return add(mul(plant, den), mul([-delay / 2, 1.0], control))


def first_order(f):
    return [1.0], [1 / (2 * math.pi * f), 1.0]


def alpha_beta(f):
    w = 2 * math.pi * f
    return [w * w], mul([1.0, w], [1.0, w])


if __name__ == "__main__":
    cases = [("encoders, 10 Hz first-order", first_order(10.0))] + [
        (f"alpha-beta filter, {f} Hz", alpha_beta(f)) for f in (40.0, 80.0, 150.0)
    ]
    for kp, kd in [(400.0, 40.0), (400.0, 20.0)]:
        for label, filt in cases:
            zeta, w = least_damped(loop(kp, kd, filt))
            print(f"K_p {kp:.0f}, K_d {kd:.0f}, {label:30s}: zeta {zeta:.2f} at {w / (2 * math.pi):.1f} Hz")
