#!/usr/bin/python3
"""Renders the synthetic RGB-D sample session shipped in test/data/sample_session.

A tabletop scene (table plane, three boxes, a cylinder) seen by a PrimeSense-like camera
(640x480, fx = fy = 525, cx = 319.5, cy = 239.5) moving slowly along an arc. Per frame:
  sampleN_rgb.png          8-bit RGB, Lambert shading of textured surfaces plus sensor noise
  sampleN_depth_mm.png     16-bit depth in millimetres along the optical axis, 0 = invalid;
                           disparity-quantised with depth-dependent noise, no depth beyond 3.5 m
                           and holes at depth discontinuities, as a structured-light sensor has them
  sampleN_label_object.png 16-bit object label: 0 = nothing, 1 = table, k >= 2 = object k
  poses.txt                camera poses (TUM format: t tx ty tz qx qy qz qw, world frame, metres)
Deterministic: the noise generator is seeded, so re-running reproduces the files bit for bit.
Usage: make_sample_session.py OUTPUT_FOLDER [FRAMES]
"""
import math
import os
import struct
import sys
import zlib

import numpy as np

WIDTH, HEIGHT = 640, 480
FX = FY = 525.0
CX, CY = 319.5, 239.5


def write_png(path, image):
    """Writes an 8-bit RGB (H, W, 3) or 16-bit grey (H, W) numpy image as PNG."""
    if image.ndim == 3:
        color_type, bit_depth = 2, 8
        raw = image.astype(np.uint8)
    else:
        color_type, bit_depth = 0, 16
        raw = image.astype(">u2")
    rows = raw.reshape(raw.shape[0], -1).view(np.uint8).reshape(raw.shape[0], -1)
    data = b"".join(b"\x00" + row.tobytes() for row in rows)

    def chunk(tag, payload):
        return struct.pack(">I", len(payload)) + tag + payload + struct.pack(">I", zlib.crc32(tag + payload) & 0xFFFFFFFF)

    header = struct.pack(">IIBBBBB", image.shape[1], image.shape[0], bit_depth, color_type, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(data, 9)) + chunk(b"IEND", b""))


def look_at(eye, target, up=np.array([0.0, 0.0, 1.0])):
    """Rotation camera->world of an optical frame (z forward, x right, y down) looking at target."""
    z = target - eye
    z /= np.linalg.norm(z)
    x = np.cross(z, up)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=1)


def quaternion(r):
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2.0
    return ((r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w), (r[1, 0] - r[0, 1]) / (4 * w), w)


# World frame: z up, table top at z = 0. Boxes as (min corner, max corner, base colour RGB, label).
BOXES = [
    (np.array([-0.25, 0.05, 0.0]), np.array([-0.05, 0.25, 0.18]), np.array([200, 60, 50]), 2),
    (np.array([0.02, 0.10, 0.0]), np.array([0.16, 0.22, 0.10]), np.array([60, 110, 200]), 3),
    (np.array([0.05, -0.18, 0.0]), np.array([0.30, -0.02, 0.06]), np.array([210, 190, 70]), 4),
]
CYLINDER = (np.array([-0.18, -0.15]), 0.05, 0.22, np.array([70, 170, 90]), 5)  # centre xy, radius, height
TABLE = (np.array([-0.6, -0.5]), np.array([0.6, 0.6]), np.array([150, 120, 95]), 1)  # xy extent


def render(eye, rotation, rng):
    u, v = np.meshgrid(np.arange(WIDTH), np.arange(HEIGHT))
    rays_cam = np.stack([(u - CX) / FX, (v - CY) / FY, np.ones_like(u, dtype=float)], axis=-1)
    d = rays_cam @ rotation.T  # world directions, not unit: t is the optical-axis depth
    best_t = np.full((HEIGHT, WIDTH), np.inf)
    normal = np.zeros((HEIGHT, WIDTH, 3))
    label = np.zeros((HEIGHT, WIDTH), dtype=np.int32)
    base = np.zeros((HEIGHT, WIDTH, 3))

    def take(t, n, colour, lab, mask):
        hit = mask & (t > 1e-6) & (t < best_t)
        best_t[hit] = t[hit]
        normal[hit] = n[hit] if n.ndim == 3 else n
        base[hit] = colour
        label[hit] = lab

    with np.errstate(divide="ignore", invalid="ignore"):
        # Table top.
        t = -eye[2] / d[..., 2]
        p = eye + t[..., None] * d
        inside = (p[..., 0] > TABLE[0][0]) & (p[..., 0] < TABLE[1][0]) & (p[..., 1] > TABLE[0][1]) & (p[..., 1] < TABLE[1][1])
        take(t, np.array([0.0, 0.0, 1.0]), TABLE[2], TABLE[3], inside)
        # Boxes (slab method), with the face normal of the entry slab.
        for lo, hi, colour, lab in BOXES:
            t0 = (lo - eye) / d
            t1 = (hi - eye) / d
            tmin = np.minimum(t0, t1)
            tmax = np.maximum(t0, t1)
            t_enter = tmin.max(axis=-1)
            t_exit = tmax.min(axis=-1)
            axis = tmin.argmax(axis=-1)
            n = np.zeros((HEIGHT, WIDTH, 3))
            for k in range(3):
                n[..., k] = np.where(axis == k, -np.sign(d[..., k]), 0.0)
            take(t_enter, n, colour, lab, t_enter < t_exit)
        # Cylinder side and top.
        (cx, cy), radius, height, colour, lab = CYLINDER
        ox, oy = eye[0] - cx, eye[1] - cy
        a = d[..., 0] ** 2 + d[..., 1] ** 2
        b = 2 * (ox * d[..., 0] + oy * d[..., 1])
        c = ox * ox + oy * oy - radius * radius
        disc = b * b - 4 * a * c
        t = (-b - np.sqrt(np.maximum(disc, 0))) / (2 * a)
        z = eye[2] + t * d[..., 2]
        p = eye + t[..., None] * d
        n = np.stack([(p[..., 0] - cx) / radius, (p[..., 1] - cy) / radius, np.zeros_like(t)], axis=-1)
        take(t, n, colour, lab, (disc > 0) & (z > 0) & (z < height))
        t = (height - eye[2]) / d[..., 2]
        p = eye + t[..., None] * d
        take(t, np.array([0.0, 0.0, 1.0]), colour, lab, (p[..., 0] - cx) ** 2 + (p[..., 1] - cy) ** 2 < radius * radius)

    hit = np.isfinite(best_t)
    point = eye + np.where(hit, best_t, 0)[..., None] * d
    # Procedural texture (fine stripes and a checker) so colour is not constant on a surface.
    texture = 0.85 + 0.1 * np.sign(np.sin(point[..., 0] * 60) * np.sin(point[..., 1] * 60)) + 0.05 * np.sin(point[..., 2] * 150)
    light = np.array([0.3, -0.4, 0.85])
    light /= np.linalg.norm(light)
    shade = 0.35 + 0.65 * np.clip(normal @ light, 0, 1)
    rgb = base * (shade * texture)[..., None] + rng.normal(0, 2.0, base.shape)
    rgb = np.where(hit[..., None], rgb, 40.0)
    rgb = np.clip(rgb, 0, 255).astype(np.uint8)

    # Depth: optical-axis distance (t, since rays have unit z in the camera), Kinect-like
    # disparity quantisation (1/8 pixel at 7.5 cm baseline) and noise growing with z^2.
    z = np.where(hit, best_t, 0.0)
    valid = hit & (z > 0.4) & (z < 3.5)
    disparity = np.round(0.075 * FX * 8 / np.where(valid, z, 1)) / 8
    z_quant = 0.075 * FX / np.maximum(disparity, 1e-6)
    z_noisy = z_quant + rng.normal(0, 1, z.shape) * 0.0012 * z_quant ** 2
    # Holes where depth jumps (structured-light shadows) and a few random dropouts.
    jump = np.zeros_like(valid)
    zz = np.where(valid, z, 0)
    jump[:, 1:] |= np.abs(zz[:, 1:] - zz[:, :-1]) > 0.05
    jump[:, :-1] |= np.abs(zz[:, 1:] - zz[:, :-1]) > 0.05
    valid &= ~jump & (rng.random(z.shape) > 0.002)
    depth_mm = np.where(valid, np.round(z_noisy * 1000), 0).astype(np.uint16)
    label = np.where(hit, label, 0).astype(np.uint16)
    return rgb, depth_mm, label


def main():
    out = sys.argv[1]
    frames = int(sys.argv[2]) if len(sys.argv) > 2 else 6
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(20131122)
    target = np.array([0.0, 0.03, 0.05])
    with open(os.path.join(out, "poses.txt"), "w") as poses:
        poses.write("# timestamp tx ty tz qx qy qz qw (world: z up, table top at z = 0; camera optical frame)\n")
        for i in range(frames):
            angle = math.radians(-100 + 2.0 * i)  # slow arc around the table, 2 degrees a frame
            eye = np.array([0.9 * math.cos(angle), 0.9 * math.sin(angle), 0.75])
            rotation = look_at(eye, target)
            rgb, depth, label = render(eye, rotation, rng)
            write_png(os.path.join(out, f"sample{i}_rgb.png"), rgb)
            write_png(os.path.join(out, f"sample{i}_depth_mm.png"), depth)
            write_png(os.path.join(out, f"sample{i}_label_object.png"), label)
            q = quaternion(rotation)
            poses.write(f"{i / 30.0:.6f} {eye[0]:.6f} {eye[1]:.6f} {eye[2]:.6f} {q[0]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f}\n")


if __name__ == "__main__":
    main()
