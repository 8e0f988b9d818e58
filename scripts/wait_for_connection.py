#!/usr/bin/python3
"""Waits until NODE has a connected subscription to TOPIC (from any publisher).

Usage: wait_for_connection.py NODE TOPIC [TIMEOUT_S]. Exits 0 once the node's bus info shows an
inbound connection on the topic that is up, 1 after the timeout (default 30 s).
A node that has subscribed receives a publisher's messages only once that connection is up:
make demo starts the emulated eDVS after this, so the recorder gets the stream's first events.
"""
import sys
import time
import xmlrpc.client

import rosgraph
import rosnode


def connected(node, topic):
    try:
        api = rosnode.get_api_uri(rosgraph.Master("/wait_for_connection"), node, skip_cache=True)
        if not api:
            return False
        code, _, info = xmlrpc.client.ServerProxy(api).getBusInfo("/wait_for_connection")
    except (OSError, rosnode.ROSNodeIOException, xmlrpc.client.Error):
        return False
    # Each entry: connection id, destination, direction ('i' inbound), transport, topic, connected.
    return code == 1 and any(len(c) > 5 and c[2] == "i" and c[4] == topic and c[5] for c in info)


def main():
    node, topic = sys.argv[1], sys.argv[2]
    timeout = float(sys.argv[3]) if len(sys.argv) > 3 else 30.0
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if connected(node, topic):
            return 0
        time.sleep(0.1)
    print(f"wait_for_connection: {node} has no connection on {topic} after {timeout:.0f} s", file=sys.stderr)
    return 1


if __name__ == "__main__":
    sys.exit(main())
