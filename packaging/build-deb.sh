#!/bin/bash
# Builds the drivegate Debian package from this source tree:
#
#   packaging/build-deb.sh
#
# Stages the tree (git's tracked and untracked-but-not-ignored files, so no build directory)
# with packaging/debian/ as debian/ in packaging/stage/drivegate-VERSION/, and runs
# `dpkg-buildpackage -b -us -uc` there. The results are left in packaging/stage/:
#   drivegate_VERSION_ARCH.deb, drivegate-dbgsym_VERSION_ARCH.deb, .buildinfo, .changes
# Build dependencies: `apt-get build-dep ./packaging/stage/drivegate-VERSION` after a first
# staging, or the Build-Depends of packaging/debian/control (packaging/ci-check.sh installs them).
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
top="$(cd "$here/.." && pwd)"
stage="$here/stage"

# The package's version is the changelog's; it must be the one CMake builds into the programs.
version="$(dpkg-parsechangelog -l "$here/debian/changelog" -S Version)"
cmake_version="$(sed -n 's/^project(drivegate VERSION \([0-9.]*\).*/\1/p' "$top/CMakeLists.txt")"
if [ "$version" != "$cmake_version" ]; then
    echo "build-deb.sh: debian/changelog says $version, CMakeLists.txt $cmake_version" >&2
    exit 1
fi

src="$stage/drivegate-$version"
rm -rf "$stage"
mkdir -p "$src"
if git -C "$top" rev-parse --is-inside-work-tree >/dev/null 2>&1; then
    # Files deleted in the working tree are listed by git but gone: skip them.
    # shellcheck disable=SC2016 # expanded by the inner sh
    (cd "$top" && git ls-files -z --cached --others --exclude-standard) |
        (cd "$top" && xargs -0 -r sh -c 'for f; do [ -e "$f" ] && printf "%s\0" "$f"; done' sh) |
        tar -C "$top" --null --no-recursion -T - -cf - | tar -C "$src" -xf -
else
    tar -C "$top" --exclude='./build*' --exclude=./packaging/stage --exclude=./.git -cf - . |
        tar -C "$src" -xf -
fi
rm -rf "$src/debian"
cp -a "$here/debian" "$src/debian"

jobs="$(nproc 2>/dev/null || echo 1)"
export DEB_BUILD_OPTIONS="${DEB_BUILD_OPTIONS:-parallel=$jobs}"
(cd "$src" && dpkg-buildpackage -b -us -uc)

ls -1 "$stage"/*.deb
