#!/usr/bin/env bash
# Copies Debian's SQLite, zstd and LMDB (headers + shared libraries) into DEST (default:
# .device/store under the current git checkout) so that the GPU machine, which has none of the
# -dev packages, builds the page stores (fragg_map_store) and the paging tests. Installs the
# -dev packages here first if they are missing. scripts/device_check.sh passes
# -DSTORE_ROOT=$PWD/.device/store and LD_LIBRARY_PATH=$PWD/.device/store/lib when it exists.
set -euo pipefail
top=$(git rev-parse --show-toplevel 2>/dev/null || pwd)
dest=${1:-$top/.device/store}
lib=/usr/lib/x86_64-linux-gnu
if [ ! -f /usr/include/sqlite3.h ] || [ ! -f /usr/include/zstd.h ] || [ ! -f /usr/include/lmdb.h ]; then
  (apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
    libsqlite3-dev libzstd-dev liblmdb-dev) >/dev/null
fi
rm -rf "$dest" && mkdir -p "$dest/include" "$dest/lib"
cp -a /usr/include/sqlite3.h /usr/include/sqlite3ext.h /usr/include/zstd.h \
  /usr/include/zstd_errors.h /usr/include/zdict.h /usr/include/lmdb.h "$dest/include/"
cp -a "$lib"/libsqlite3.so* "$lib"/libzstd.so* "$lib"/liblmdb.so* "$dest/lib/"
for p in libsqlite3-dev libzstd-dev liblmdb-dev; do
  echo "$p $(dpkg-query -W -f='${Version}' "$p" 2>/dev/null || echo unknown)"
done > "$dest/VERSION"
echo "staged the page store libraries in $dest ($(du -sh "$dest" | cut -f1)):"
cat "$dest/VERSION"
