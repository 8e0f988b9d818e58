#!/usr/bin/python3
"""Runs the C++ and the Python example subscriber for two frames each against the live pipeline
and checks what they print: per segment a superpixel count and a 3D centre in front of the
camera, the counts adding up to the frame's superpixels."""
import re
import subprocess
import unittest

import rostest

LINE = re.compile(r"segment (-?\d+): (\d+) superpixels, centre \((-?[\d.]+), (-?[\d.]+), (-?[\d.]+)\) m")
FRAME = re.compile(r"frame [\d.]+ in (\S+): (\d+) superpixels, (\d+) segments")
REMAP = ["superpixels:=/camera/superpixels", "segmentation:=/camera/segmentation", "_frames:=2"]


def check(test, output):
    frames = [FRAME.match(l) for l in output.splitlines() if l.startswith("frame ")]
    test.assertEqual(len(frames), 2, output)
    blocks = output.split("frame ")[1:]
    for frame, block in zip(frames, blocks):
        test.assertEqual(frame.group(1), "camera_rgb_optical_frame")
        segments = [LINE.match(l) for l in block.splitlines()[1:] if l.startswith("segment ")]
        test.assertEqual(len(segments), int(frame.group(3)))
        test.assertGreater(len(segments), 1)
        test.assertEqual(sum(int(m.group(2)) for m in segments), int(frame.group(2)))
        for m in segments:
            test.assertGreater(float(m.group(5)), 0.2)  # in front of the camera [m]


class Examples(unittest.TestCase):
    def test_cpp_example(self):
        out = subprocess.run(["rosrun", "dasp_ros", "example_segment_centres"] + REMAP,
                             capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stderr)
        check(self, out.stdout)

    def test_python_example(self):
        out = subprocess.run(["rosrun", "dasp_ros", "segment_centres.py"] + REMAP,
                             capture_output=True, text=True, timeout=60)
        self.assertEqual(out.returncode, 0, out.stderr)
        check(self, out.stdout)


if __name__ == "__main__":
    rostest.rosrun("dasp_ros", "examples_test", Examples)
