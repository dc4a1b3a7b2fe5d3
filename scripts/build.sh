#!/usr/bin/env bash
# Builds fragg_map as a catkin package: installs the missing Debian packages, links the
# repository into a catkin workspace beside it (<checkout>_ws by default) and runs catkin_make
# in Release. Without an installed octomap_msgs (Debian packages none), the messages-only
# stand-in (test/octomap_msgs_standin: octomap_msgs' definitions, the same md5sums) is built
# first in <ws>/octomap_msgs_standin, so that octomap_binary / octomap_full and the GetOctomap
# services exist; with a ros.org octomap_msgs installed, that one is used.
# The CLI lands in <ws>/devel/lib/fragg_map/fragg_map.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

fragg_usage() {
  echo "usage: bash scripts/build.sh [options]"
  fragg_usage_common
}
fragg_parse_common "$@"

fragg_install_deps
fragg_octomap_msgs_standin
fragg_build_ws
echo
echo "build: OK in $(fragg_elapsed): $FRAGG_WS/devel/lib/fragg_map/fragg_map"
