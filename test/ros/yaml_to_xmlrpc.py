#!/usr/bin/python3
"""Merges YAML parameter files (later ones override, as successive <rosparam> loads do) and
prints the result as one XML-RPC value, the form ros::NodeHandle::getParam returns."""
import sys
import xmlrpc.client

import yaml


def merge(base, extra):
    for key, value in extra.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            merge(base[key], value)
        else:
            base[key] = value
    return base


def main():
    params = {}
    for path in sys.argv[1:]:
        with open(path) as f:
            merge(params, yaml.safe_load(f) or {})
    xml = xmlrpc.client.dumps((params,), allow_none=False)
    start = xml.index("<value>")
    end = xml.rindex("</value>") + len("</value>")
    sys.stdout.write(xml[start:end])


if __name__ == "__main__":
    main()
