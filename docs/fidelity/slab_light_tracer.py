#!/usr/bin/env python3
"""An independent check of docs/fidelity.md's slab rows: light tracing through a homogeneous slab.

Photons leave the sun, travel through the slab (optical depth TAU, albedo 0.999) scattering with
the Jendersie-d'Eon 10 um phase ("jd") or HG 0.8 ("hg"), sampled from a tabulated inverse CDF;
every collision is scored toward the camera's pixel directions (a point estimator: phase x
transmittance to the slab's bottom along the view / |mu_view|), in the fidelity program's units
(sun illuminance 10). The views are the fidelity program's: camera below the slab, 32x18 pixels,
20 deg vertical field of view, looking up at 90, 55 and 20 deg elevation away from the sun's
azimuth; a 8x6 subset of their pixel directions is averaged.

Unlike the path tracer (camera paths with next-event estimation toward the sun), the photons
travel where this phase's narrow forward peak sends them, so the peak does not make fireflies.

    python3 docs/fidelity/slab_light_tracer.py jd 1 30 2e6 [seed]   # phase, tau, sun elevation, photons

With a sixth argument `centres` it scores the centre directions of the views instead, from below
and from above (cameras above the slab looking down 90 / 55 / 20 deg away from the sun's azimuth
and 55 / 20 deg toward it: the reflected light).

src/lighting/slab_light_tracer.rs is this tracer in Rust (the same method, its own random
numbers): the slab tests in src/lighting/diffusion.rs compute their oracle with it, within 1% of
this script's numbers at 10^6 photons (HG 0.8, tau 5, sun 30 deg, the view centres above).
"""
import math
import sys

import numpy as np

PHASE, TAU, SUN_ELEVATION, PHOTONS = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(float(sys.argv[4]))
rng = np.random.default_rng(int(sys.argv[5]) if len(sys.argv) > 5 else 7)
ALBEDO = 0.999

# Jendersie & d'Eon 2023 fit at 10 um (src/lighting/phase.rs, jendersie_deon_params).
d = 10.0
G_HG = math.exp(-0.0990567 / (d - 1.67154))
G_D = math.exp(-2.20679 / (d + 3.91029) - 0.428934)
ALPHA = math.exp(3.62489 - 8.29288 / (d + 5.52825))
W_D = math.exp(-0.599085 / (d - 0.641583) - 0.664888)


def hg(c, g):
    den = (1 - g) ** 2 + 2 * g * (1 - c)
    return (1 - g * g) / (4 * np.pi * den**1.5)


def draine(c, g, a):
    return hg(c, g) * (1 + a * c * c) / (1 + a * (1 + 2 * g * g) / 3)


def phase(c):
    if PHASE == "jd":
        return (1 - W_D) * hg(c, G_HG) + W_D * draine(c, G_D, ALPHA)
    return hg(c, 0.8)


# Inverse CDF in the scattering angle, fine near the forward peak.
theta = np.concatenate([np.linspace(0, 0.3, 60000, endpoint=False), np.linspace(0.3, np.pi, 30000)])
pdf = phase(np.cos(theta)) * 2 * np.pi * np.sin(theta)
cdf = np.concatenate([[0], np.cumsum(0.5 * (pdf[1:] + pdf[:-1]) * np.diff(theta))])
cdf /= cdf[-1]


def sample_cos(n):
    return np.cos(np.interp(rng.random(n), cdf, theta))


def sun_at(elevation, azimuth):
    e, a = math.radians(elevation), math.radians(azimuth)
    return np.array([math.cos(e) * math.sin(a), math.sin(e), -math.cos(e) * math.cos(a)])


def view_directions(elevation):
    """A subset of the fidelity program's pixel directions (glam's look_at_rh, perspective_rh)."""
    forward = sun_at(elevation, 180)
    up = np.array([0, 0, 1.0]) if abs(forward[1]) > 0.99 else np.array([0, 1.0, 0])
    right = np.cross(forward, up)
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    t, aspect = math.tan(math.radians(10)), 32 / 18
    dirs = []
    for j in range(0, 18, 3):
        for i in range(0, 32, 4):
            x, y = (i + 2) / 32 * 2 - 1, 1 - (j + 1.5) / 18 * 2
            v = forward + x * t * aspect * right + y * t * up
            dirs.append(v / np.linalg.norm(v))
    return np.array(dirs)


sun = sun_at(SUN_ELEVATION, 0)  # toward the sun, y up
CENTRES = len(sys.argv) > 6 and sys.argv[6] == "centres"
if CENTRES:
    # (name, the camera's look direction): below looking up, above looking down.
    views = {
        f"{side} {e} {'toward' if a == 0 else 'away'}": np.array([sun_at(s * e, a)])
        for side, s in (("below", 1), ("above", -1))
        for e, a in ((90, 180), (55, 180), (20, 180), (55, 0), (20, 0))
    }
else:
    views = {e: view_directions(e) for e in (90, 55, 20)}
score = {e: 0.0 for e in views}
# Optical height above the slab's bottom; photons enter at the top travelling away from the sun.
z = np.full(PHOTONS, TAU)
direction = np.tile(-sun, (PHOTONS, 1))
weight = np.ones(PHOTONS)
alive = np.ones(PHOTONS, bool)
for _ in range(5000):
    idx = np.nonzero(alive)[0]
    if len(idx) == 0:
        break
    zn = z[idx] - np.log(rng.random(len(idx))) * direction[idx, 1]
    out = (zn < 0) | (zn > TAU)
    alive[idx[out]] = False
    idx = idx[~out]
    z[idx] = zn[~out]
    if len(idx) == 0:
        break
    weight[idx] *= ALBEDO
    for e, dirs in views.items():
        total = 0.0
        for v in dirs:
            # The camera looks along v; the light it sees travels along -v, out of the slab's
            # bottom (v up) or its top (v down).
            c = np.clip(direction[idx] @ (-v), -1, 1)
            out = z[idx] if v[1] > 0 else TAU - z[idx]
            total += np.sum(weight[idx] * phase(c) * np.exp(-out / abs(v[1])) / abs(v[1]))
        score[e] += total / len(dirs)
    c = sample_cos(len(idx))
    s = np.sqrt(np.maximum(1 - c * c, 0))
    phi = 2 * np.pi * rng.random(len(idx))
    dd = direction[idx]
    helper = np.where(np.abs(dd[:, 1:2]) < 0.9, np.array([[0, 1.0, 0]]), np.array([[1.0, 0, 0]]))
    t1 = np.cross(helper, dd)
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    t2 = np.cross(dd, t1)
    direction[idx] = c[:, None] * dd + (s * np.cos(phi))[:, None] * t1 + (s * np.sin(phi))[:, None] * t2

# Photons per unit horizontal area stand for the irradiance on it, 10 mu0.
norm = 10 * sun[1] / PHOTONS
print(f"{PHASE} tau {TAU:g} sun {SUN_ELEVATION:g}: " + " / ".join(f"{e}: {score[e] * norm:.5f}" for e in views))
