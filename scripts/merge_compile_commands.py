#!/usr/bin/python3
"""Merges the compile_commands.json of every package build folder into one file (for clang-tidy, editors)."""
import json
import os
import sys


def main(build_root, output):
    merged = []
    for name in sorted(os.listdir(build_root)):
        path = os.path.join(build_root, name, "compile_commands.json")
        if os.path.isfile(path):
            with open(path) as f:
                merged.extend(json.load(f))
    with open(output, "w") as f:
        json.dump(merged, f, indent=1)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
