"""Convert GRAPE's published Fig. 7 runs into afg files: datasets/grape-fig7/.

GRAPE's repository (github.com/inmo-jang/GRAPE, MIT licence) holds three MATLAB runs
of its decentralised algorithm, Fig_7_Visualisation/Result/{Circle,Skew,Square}_n320_m5.mat:
320 robots, 5 tasks, robots linked within 50 m. Each file holds the instance
(a_location, t_location, t_demand), the communication graph (MST), GRAPE's final
partition (Alloc, 1-based, 0 = the void task), its utility (Global_GRAPE, the sum of
a_utility), its final evolution number (iteration) and its rounds (final_time, one
column of Satisfied_history per round).

GRAPE's utility there (Get_Util.m, 'Logarithm_reward') is

    u_i(j, n) = t_demand_j / log2(N/M + 1) * log2(n + 1) / n - ||t_j - a_i||,

clipped at 0 (a robot with nothing positive joins the void task). That is afg's game
with every robot's selfish utility F_j(n)/n - beta d(i, j), where

    F_j(n) = r_j log_eps(n + eps - 1) with eps_j = 2 (so F_j(n) = r_j log2(n + 1)),
    r_j = t_demand_j / log2(N/M + 1), beta = 1,

no capacities, and the void task allowed ("allow_void": true). The welfare of a
partition is then the sum of the robots' utilities, GRAPE's Global_GRAPE.

Usage:
    python scripts/grape_fig7.py MAT_DIR            # write datasets/grape-fig7/
    python scripts/grape_fig7.py MAT_DIR --check    # compare with the committed files

MAT_DIR holds the three .mat files (from a clone of GRAPE, or fetched one by one).
Needs: pip install scipy numpy
"""

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np
import scipy.io

# The GRAPE commit the files were taken from.
SOURCE_COMMIT = "d2d0790274687266331fccecc01a30db0dcbdee6"
RUNS = [("circle", "Circle_n320_m5.mat"), ("skew", "Skew_n320_m5.mat"), ("square", "Square_n320_m5.mat")]
OUT = Path(__file__).resolve().parent.parent / "datasets" / "grape-fig7"


def scalar(mat, key):
    return mat[key].squeeze().item()


def point(p):
    return {"x": float(p[0]), "y": float(p[1])}


def convert(path):
    """The instance, GRAPE's partition and its published numbers of one .mat file."""
    mat = scipy.io.loadmat(path)
    robots = np.asarray(mat["a_location"], dtype=np.float64)
    tasks = np.asarray(mat["t_location"], dtype=np.float64)
    demand = np.asarray(mat["t_demand"], dtype=np.float64).ravel()
    n, m = len(robots), len(tasks)
    assert (n, m) == (scalar(mat, "n"), scalar(mat, "m")), "n and m disagree with the positions"
    radius = float(scalar(mat, "Comm_distance"))
    # The communication graph is the robots within the range of each other.
    dist = np.linalg.norm(robots[:, None, :] - robots[None, :, :], axis=2)
    disk = (dist <= radius) & ~np.eye(n, dtype=bool)
    if not np.array_equal(disk, np.asarray(mat["MST"], dtype=bool)):
        sys.exit(f"{path}: MST is not the {radius} m disk graph of the robots")
    normaliser = math.log2(n / m + 1)
    instance = {
        "format": "afg-instance",
        "version": 1,
        "beta": 1.0,
        "robots": [point(p) for p in robots],
        "tasks": [
            {"position": point(t), "reward": float(d / normaliser), "eps": 2.0}
            for t, d in zip(tasks, demand)
        ],
        "allow_void": True,
    }
    alloc = np.asarray(mat["Alloc"]).ravel().astype(int)
    assignment = {"format": "afg-assignment", "version": 1, "tasks": [int(a) - 1 for a in alloc]}
    published = {
        "utility": float(scalar(mat, "Global_GRAPE")),
        "changes": int(scalar(mat, "iteration")),
        "rounds": int(scalar(mat, "final_time")),
        "communication_range": radius,
        "links": int(disk.sum() // 2),
    }
    return instance, assignment, published


def render(mat_dir):
    """The files of datasets/grape-fig7/, by name."""
    instances, assignments, published = [], [], []
    for name, file in RUNS:
        instance, assignment, numbers = convert(Path(mat_dir) / file)
        instances.append(json.dumps(instance, separators=(",", ":")))
        assignments.append(json.dumps(assignment, separators=(",", ":")))
        published.append({"name": name, "file": file, **numbers})
    meta = {
        "format": "afg-grape-published",
        "version": 1,
        "source": "https://github.com/inmo-jang/GRAPE",
        "commit": SOURCE_COMMIT,
        "directory": "Fig_7_Visualisation/Result",
        "licence": "MIT",
        "runs": published,
    }
    return {
        "instances.jsonl": "\n".join(instances) + "\n",
        "grape-partitions.jsonl": "\n".join(assignments) + "\n",
        "published.json": json.dumps(meta, indent=2) + "\n",
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mat_dir", help="the directory holding the three .mat files")
    parser.add_argument("--check", action="store_true", help="compare with the committed files")
    parser.add_argument("--out", default=str(OUT), help="where the files go (default: %(default)s)")
    args = parser.parse_args()
    files = render(args.mat_dir)
    out = Path(args.out)
    if args.check:
        stale = [n for n, text in files.items() if not (out / n).exists() or (out / n).read_text() != text]
        if stale:
            sys.exit(f"differ from a fresh conversion: {', '.join(stale)}")
        print(f"{out}: every file equals a fresh conversion of {args.mat_dir}")
        return
    out.mkdir(parents=True, exist_ok=True)
    for name, text in files.items():
        tmp = out / (name + ".tmp")
        tmp.write_text(text)
        tmp.replace(out / name)
    print(f"wrote {', '.join(files)} to {out}")


if __name__ == "__main__":
    main()
