#!/usr/bin/env python3
"""What octomap_server's octomap_saver does, for a machine without octomap_server (Debian).

Calls the GetOctomap service (octomap_msgs/GetOctomap: `octomap_binary`, or `octomap_full`
with -f) and writes the tree as OctoMap's file: the .bt header (`# Octomap OcTree binary file`,
id, size, res, data) and the message's data as received, or the .ot header for a full map.
Like octomap_saver it counts the tree's nodes for the header's `size`; for a binary map the
count comes from walking the stream (2 bits a child: 00 none, 01 occupied leaf, 10 free leaf,
11 inner node), which also checks that the stream is a whole tree.

    octomap_saver.py [-f] OUTPUT.bt|OUTPUT.ot [--service NAME] [--timeout S]

On a ROS install with octomap_server, `rosrun octomap_server octomap_saver` is the same call.
"""
import argparse
import sys

import rospy
from octomap_msgs.srv import GetOctomap


def binary_tree_nodes(data):
    """Nodes of a binary (.bt) stream: the root and every child listed; raises on a short
    stream or bytes left over."""
    pos = 0
    nodes = 1
    pending = 1  # nodes whose two child bytes are still to read
    while pending:
        if pos + 2 > len(data):
            raise ValueError("the binary stream ends inside the tree (%d bytes)" % len(data))
        bits = data[pos] | (data[pos + 1] << 8)  # children 0-3, then 4-7, 2 bits each
        pos += 2
        pending -= 1
        for child in range(8):
            code = (bits >> (2 * child)) & 3
            if code:
                nodes += 1
            if code == 3:
                pending += 1
    if pos != len(data):
        raise ValueError("%d bytes after the tree's end" % (len(data) - pos))
    return nodes


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", help="file to write (.bt, or .ot with -f)")
    parser.add_argument("-f", "--full", action="store_true", help="the full map (octomap_full)")
    parser.add_argument("--service", help="service name (default octomap_binary / octomap_full)")
    parser.add_argument("--timeout", type=float, default=30.0, help="seconds to wait for it")
    args = parser.parse_args(rospy.myargv()[1:])
    service = args.service or ("octomap_full" if args.full else "octomap_binary")
    rospy.init_node("octomap_saver", anonymous=True, disable_signals=True)
    print("Requesting the map from %s" % rospy.resolve_name(service))
    try:
        rospy.wait_for_service(service, timeout=args.timeout)
        msg = rospy.ServiceProxy(service, GetOctomap)().map
    except (rospy.ROSException, rospy.ServiceException) as e:
        sys.exit("octomap_saver.py: %s: %s" % (service, e))
    data = bytes(bytearray((b + 256) % 256 for b in msg.data))  # int8[] arrives signed
    if msg.binary:
        if not args.output.endswith(".bt"):
            sys.exit("octomap_saver.py: a binary map is written as .bt, not %s" % args.output)
        size = binary_tree_nodes(data)
        header = "# Octomap OcTree binary file\nid %s\nsize %d\nres %s\ndata\n"
    else:
        if not args.output.endswith(".ot"):
            sys.exit("octomap_saver.py: a full map is written as .ot, not %s" % args.output)
        # A full stream carries each node's value: its count needs the tree class; liboctomap
        # reads an .ot's `size` line and ignores it.
        size = 0
        header = "# Octomap OcTree file\nid %s\nsize %d\nres %s\ndata\n"
    with open(args.output, "wb") as f:
        f.write((header % (msg.id, size, repr(msg.resolution))).encode())
        f.write(data)
    print("Map received (%d nodes, %s m), saved to %s" % (size, msg.resolution, args.output))


if __name__ == "__main__":
    main()
