#!/usr/bin/python3
"""Pose-by-pose comparison of two TUM trajectories at equal times (same_results.sh):
   compare_trajectories.py A.tum A_TIME_OFFSET_S B.tum
A's times minus A_TIME_OFFSET_S are matched to B's times to the microsecond; prints the counts and
the largest and mean position difference [m] over the matched poses."""
import sys


def read(path, offset_s):
    poses = {}
    for line in open(path):
        if line.startswith('#') or not line.strip():
            continue
        v = [float(x) for x in line.split()]
        poses[round((v[0] - offset_s) * 1e6)] = v[1:3]
    return poses


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    a, b = read(sys.argv[1], float(sys.argv[2])), read(sys.argv[3], 0.0)
    common = sorted(set(a) & set(b))
    diffs = [((a[t][0] - b[t][0]) ** 2 + (a[t][1] - b[t][1]) ** 2) ** 0.5 for t in common]
    if not diffs:
        sys.exit('%s and %s have no pose at the same time' % (sys.argv[1], sys.argv[3]))
    print('%s: %d poses, %s: %d, %d at the same time; position difference max %.6f m, mean %.6f m'
          % (sys.argv[1], len(a), sys.argv[3], len(b), len(common), max(diffs),
             sum(diffs) / len(diffs)))


if __name__ == '__main__':
    main()
