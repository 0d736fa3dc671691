"""Writes opencv_pnp_cases.json: PnP problems solved by OpenCV's solvePnP (SQPNP and
ITERATIVE), for crates/pose/tests/pnp_vs_opencv.rs.

    pip install opencv-python-headless numpy
    python3 crates/pose/tests/data/make_opencv_cases.py

Bodies are 16 mm cubes carrying 10.6 mm square tags (corners and centre) on the faces turned
toward a 1500 px camera at 60-140 mm; noise-free cases carry radial distortion, noisy ones
(0.2 px) none, so that OpenCV's ITERATIVE minimises exactly what ours does.
"""
import json
import os

import cv2
import numpy as np

rng = np.random.default_rng(20261122)
K = np.array([[1500.0, 0, 959.5], [0, 1500.0, 539.5], [0, 0, 1]])


def tag_points(face):
    normals = [np.eye(3)[0], np.eye(3)[1], np.eye(3)[2], -np.eye(3)[0], -np.eye(3)[1], -np.eye(3)[2]]
    n = normals[face]
    a = np.eye(3)[0] if abs(n[0]) < 0.5 else np.eye(3)[1]
    u = np.cross(n, a)
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    turn = 0.3 * face
    u, v = u * np.cos(turn) + v * np.sin(turn), v * np.cos(turn) - u * np.sin(turn)
    c, h = n * 8.0, 5.3
    return [c - u * h + v * h, c + u * h + v * h, c + u * h - v * h, c - u * h - v * h, c], n


cases = []
while len(cases) < 40:
    noisy = len(cases) % 2 == 1
    dist = np.zeros(5) if noisy else np.array([0.05, -0.02, 0, 0, 0])
    axis = rng.uniform(-1, 1, 3)
    rvec = axis / np.linalg.norm(axis) * rng.uniform(0, 3)
    tvec = np.array([rng.uniform(-20, 20), rng.uniform(-10, 10), rng.uniform(60, 140)])
    R, _ = cv2.Rodrigues(rvec)
    obj, ids = [], []
    for face in range(6):
        pts, n = tag_points(face)
        c = R @ (n * 8.0) + tvec
        if -(R @ n) @ (c / np.linalg.norm(c)) > 0.2:
            obj += pts
            ids += [face] * 5
    if len(obj) < 10:  # keep two tags or more: single tags are ambiguous for every solver
        continue
    obj = np.array(obj)
    px, _ = cv2.projectPoints(obj, rvec, tvec, K, dist)
    px = px.reshape(-1, 2)
    if noisy:
        px = px + rng.normal(0, 0.2, px.shape)
    out = {}
    for name, flag in [("sqpnp", cv2.SOLVEPNP_SQPNP), ("iterative", cv2.SOLVEPNP_ITERATIVE)]:
        ok, r, t = cv2.solvePnP(obj, px, K, dist, flags=flag)
        assert ok
        if name == "iterative":
            r, t = cv2.solvePnPRefineLM(obj, px, K, dist, r, t, (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_COUNT, 200, 1e-15))
        out[name] = {"rvec": r.ravel().tolist(), "tvec": t.ravel().tolist()}
    cases.append({
        "noise_px": 0.2 if noisy else 0.0,
        "camera": {"fx": 1500.0, "fy": 1500.0, "cx": 959.5, "cy": 539.5, "k1": dist[0], "k2": dist[1]},
        "truth": {"rvec": rvec.tolist(), "tvec": tvec.tolist()},
        "points": [{"tag": int(i), "body": b.tolist(), "pixel": p.tolist()} for i, b, p in zip(ids, obj, px)],
        "opencv": out,
    })

path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "opencv_pnp_cases.json")
with open(path, "w") as f:
    json.dump({"generator": f"make_opencv_cases.py, OpenCV {cv2.__version__}", "cases": cases}, f, indent=1)
print(f"wrote {len(cases)} cases to {path}")
