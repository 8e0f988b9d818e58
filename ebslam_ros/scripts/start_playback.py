#!/usr/bin/python3
"""Starts a paused `rosbag play` once the nodes that process the bag have subscribed.

`rosbag play --delay` guesses how long nodes need to start; on a loaded or cold machine they may
need longer and miss the first messages. This node waits (wall clock: /clock stands still while the
bag is paused) until every topic in ~topics has at least one subscriber and, for the topics the
player publishes, every subscriber the master knows is connected to the player (registration comes
before the connection: a subscriber still connecting would miss the first messages), then calls
the player's pause_playback service (std_srvs/SetBool, false = play).

Parameters:
  ~topics   topic names (a list, or one string separated by spaces), resolved in this node's
            namespace, that must have a subscriber
  ~player   the player's node name (default /player); its service is <player>/pause_playback
  ~timeout  seconds to wait before starting anyway with a warning (default 60)
"""
import time
import xmlrpc.client

import rosgraph
import rospy
from std_srvs.srv import SetBool


def unready_topics(master, topics, player):
    """The topics of `topics` without a subscriber, or published by `player` with a subscriber the
    player is not connected to yet."""
    publishers, subscribers, _ = master.getSystemState()
    subscribers = {topic: set(nodes) for topic, nodes in subscribers}
    played = {topic for topic, nodes in publishers if player in nodes}
    connected = {}
    if played & set(topics):
        try:
            _, _, bus_info = xmlrpc.client.ServerProxy(master.lookupNode(player)).getBusInfo(
                rospy.get_name())
        except (OSError, rosgraph.MasterError, xmlrpc.client.Error):
            bus_info = []
        # roscpp: [connection id, subscriber's node name, "o" (outbound), transport, topic, ...]
        for info in bus_info:
            if len(info) >= 5 and info[2] == "o":
                connected.setdefault(info[4], set()).add(info[1])
    unready = []
    for topic in topics:
        nodes = subscribers.get(topic, set()) - {player}
        if not nodes or (topic in played and not nodes <= connected.get(topic, set())):
            unready.append(topic)
    return sorted(unready)


def main():
    rospy.init_node("start_playback")
    topics = rospy.get_param("~topics", [])
    if isinstance(topics, str):
        topics = topics.split()
    topics = [rospy.resolve_name(t) for t in topics]
    player = rospy.get_param("~player", "/player")
    timeout = float(rospy.get_param("~timeout", 60.0))
    master = rosgraph.Master(rospy.get_name())
    deadline = time.monotonic() + timeout
    missing = topics
    while not rospy.is_shutdown():
        missing = unready_topics(master, topics, player)
        if not missing or time.monotonic() > deadline:
            break
        time.sleep(0.1)
    if missing:
        rospy.logwarn("start_playback: no (connected) subscriber after %.0f s on %s; starting anyway",
                      timeout, " ".join(missing))
    service = player.rstrip("/") + "/pause_playback"
    rospy.wait_for_service(service, timeout=max(1.0, deadline - time.monotonic()) + 30.0)
    reply = rospy.ServiceProxy(service, SetBool)(False)
    if not reply.success:  # the player was not paused (started without --pause, or by hand)
        rospy.logwarn("start_playback: %s: %s", service, reply.message)
    rospy.loginfo("start_playback: playing (%d topics subscribed)", len(topics) - len(missing))


if __name__ == "__main__":
    main()
