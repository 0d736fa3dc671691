"""OpenCV's solvePnP for tracker-bench: the PnP half of the reference stack.

    pip install opencv-python-headless
    (run by `tracker-bench`, one process for the whole run; not meant to be run by hand)

Protocol, one JSON object per line:

- on start it writes {"opencv": "<version>"};
- each request on stdin is {"camera": [fx, fy, cx, cy, k1, k2],
  "bodies": [{"object": [[x, y, z], ...], "image": [[u, v], ...]}, ...]} (mm, px; pixel centres
  at integer coordinates, the same convention as the camera matrix);
- each answer on stdout is {"poses": [...]}, one entry per body in order: either
  {"rvec": [...], "tvec": [...], "sqpnp_us": t, "iterative_us": t} with the SOLVEPNP_SQPNP pose
  (object to camera) and the median time (µs) of `REPEATS` calls of each of SQPNP and
  ITERATIVE on the same points, or {"error": "..."} when OpenCV found no pose.
"""
import json
import math
import statistics
import sys
import time

import cv2
import numpy as np

REPEATS = 5


def timed(obj, img, K, dist, flag):
    """The pose of the first call and the median time (µs) of REPEATS calls."""
    times = []
    result = None
    for _ in range(REPEATS):
        start = time.perf_counter_ns()
        out = cv2.solvePnP(obj, img, K, dist, flags=flag)
        times.append((time.perf_counter_ns() - start) / 1000.0)
        if result is None:
            result = out
    return result, statistics.median(times)


def solve(body, K, dist):
    obj = np.ascontiguousarray(body["object"], dtype=np.float64).reshape(-1, 3)
    img = np.ascontiguousarray(body["image"], dtype=np.float64).reshape(-1, 2)
    try:
        (ok, rvec, tvec), sqpnp_us = timed(obj, img, K, dist, cv2.SOLVEPNP_SQPNP)
        _, iterative_us = timed(obj, img, K, dist, cv2.SOLVEPNP_ITERATIVE)
    except cv2.error as e:
        lines = str(e).strip().splitlines()
        return {"error": lines[-1] if lines else "cv2.error"}
    rvec, tvec = rvec.ravel().tolist(), tvec.ravel().tolist()
    if not ok or not all(math.isfinite(v) for v in rvec + tvec):
        return {"error": "SQPnP found no pose"}
    return {"rvec": rvec, "tvec": tvec, "sqpnp_us": sqpnp_us, "iterative_us": iterative_us}


def main():
    print(json.dumps({"opencv": cv2.__version__}), flush=True)
    for line in sys.stdin:
        if not line.strip():
            continue
        request = json.loads(line)
        fx, fy, cx, cy, k1, k2 = request["camera"]
        K = np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]])
        dist = np.array([k1, k2, 0.0, 0.0])
        poses = [solve(body, K, dist) for body in request["bodies"]]
        print(json.dumps({"poses": poses}), flush=True)


if __name__ == "__main__":
    main()
