"""OpenCV's solvePnP (SQPNP and ITERATIVE) timed on correspondences from `jawtrack bench pipeline`.

Reads JSON lines on stdin: first {"camera": {fx, fy, cx, cy, k1, k2}, "repeat": N}, then one
{"body": [[x, y, z], ...], "pixel": [[u, v], ...]} per solved body. Writes one JSON line per
body: for each method the pose (rvec, tvec in mm) and the median time of N calls (µs).
"""
import json
import sys
import time

import cv2
import numpy as np

METHODS = {"sqpnp": cv2.SOLVEPNP_SQPNP, "iterative": cv2.SOLVEPNP_ITERATIVE}


def main():
    head = json.loads(sys.stdin.readline())
    c = head["camera"]
    K = np.array([[c["fx"], 0.0, c["cx"]], [0.0, c["fy"], c["cy"]], [0.0, 0.0, 1.0]])
    dist = np.array([c.get("k1", 0.0), c.get("k2", 0.0), 0.0, 0.0, 0.0])
    repeat = int(head["repeat"])
    for line in sys.stdin:
        case = json.loads(line)
        obj = np.array(case["body"], dtype=np.float64)
        img = np.array(case["pixel"], dtype=np.float64)
        out = {}
        for name, flag in METHODS.items():
            times = []
            for _ in range(repeat):
                t0 = time.perf_counter_ns()
                ok, rvec, tvec = cv2.solvePnP(obj, img, K, dist, flags=flag)
                times.append(time.perf_counter_ns() - t0)
            times.sort()
            out[name] = {
                "ok": bool(ok),
                "rvec": rvec.ravel().tolist(),
                "tvec": tvec.ravel().tolist(),
                "us": times[len(times) // 2] / 1e3,
            }
        print(json.dumps(out), flush=True)


if __name__ == "__main__":
    main()
