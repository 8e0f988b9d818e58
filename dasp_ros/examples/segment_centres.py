#!/usr/bin/python3
"""Example subscriber: reads `superpixels` (ebslam_msgs/SuperpixelArray) and `segmentation`
(ebslam_msgs/Segmentation) of the same frame and prints, per segment, its number of superpixels
and its 3D centre (pixel-weighted mean of its superpixels' centres, metres, in the header's frame).
~frames: exit after this many frames (0 = run until shut down).
  rosrun dasp_ros segment_centres.py superpixels:=/camera/superpixels segmentation:=/camera/segmentation
"""
import collections

import message_filters
import rospy
from ebslam_msgs.msg import Segmentation, SuperpixelArray


def main():
    rospy.init_node("segment_centres_py")
    max_frames = rospy.get_param("~frames", 0)
    frames = [0]

    def callback(array, segmentation):
        if len(segmentation.segment_ids) != len(array.superpixels):
            rospy.logwarn("segmentation and superpixels differ in size")
            return
        sums = collections.defaultdict(lambda: [0, 0.0, 0.0, 0.0, 0.0])
        for sp, segment in zip(array.superpixels, segmentation.segment_ids):
            s = sums[segment]
            w = float(sp.pixel_count)
            s[0] += 1
            s[1] += w
            s[2] += w * sp.position.x
            s[3] += w * sp.position.y
            s[4] += w * sp.position.z
        print(f"frame {array.header.stamp.to_sec():.3f} in {array.header.frame_id}: "
              f"{len(array.superpixels)} superpixels, {len(sums)} segments")
        for segment in sorted(sums):
            n, w, x, y, z = sums[segment]
            print(f"segment {segment}: {n} superpixels, centre ({x / w:.3f}, {y / w:.3f}, {z / w:.3f}) m")
        print("", end="", flush=True)
        frames[0] += 1
        if max_frames > 0 and frames[0] >= max_frames:
            rospy.signal_shutdown("done")

    superpixels = message_filters.Subscriber("superpixels", SuperpixelArray)
    segmentation = message_filters.Subscriber("segmentation", Segmentation)
    message_filters.TimeSynchronizer([superpixels, segmentation], 10).registerCallback(callback)
    rospy.spin()


if __name__ == "__main__":
    main()
