"""Times pydelatin on one raw f32 grid exported by
`cargo run --release -p cota-bench --bin export-grid -- raw NAME FILE`.

Usage: python3 pydelatin_bench.py FILE WIDTH HEIGHT NAME E1,E2,... [MIN_E]
Prints tab-separated lines: NAME pydelatin run E median_ms min_ms runs triangles.
"""
import sys
import time

import numpy as np
from pydelatin import Delatin


def main():
    path, w, h, name, es = sys.argv[1:6]
    min_e = float(sys.argv[6]) if len(sys.argv) > 6 else 0.0
    width, height = int(w), int(h)
    grid = np.fromfile(path, dtype="<f4", count=width * height).reshape(height, width)
    for e in (float(x) for x in es.split(",")):
        if e < min_e:
            continue
        ms, tin = [], None
        t0 = time.perf_counter()
        while len(ms) < 3 or (len(ms) < 15 and time.perf_counter() - t0 < 1.0):
            t = time.perf_counter()
            tin = Delatin(grid, width=width, height=height, max_error=e)
            ms.append((time.perf_counter() - t) * 1e3)
        ms.sort()
        e_txt = f"{e:g}"
        print(f"{name}\tpydelatin\trun\t{e_txt}\t{ms[len(ms) // 2]:.2f}\t{ms[0]:.2f}\t{len(ms)}\t{len(tin.triangles)}")


if __name__ == "__main__":
    main()
