#!/usr/bin/env bash
# The add-on zip where it was not built: a bare Debian 12 root (debootstrap --variant=minbase
# bookworm) with nothing but Debian's `blender` and `python3-numpy` (no recommends), the zip
# installed as a user installs it (Preferences > Add-ons > Install, headless), then
# triangulate, polygonize and smooth through the add-on's operators, each giving a closed mesh
# (scripts/portable_addon_check.py). Before the zip carried its libraries this failed with
# "libOpenMeshCore.so.9.0: cannot open shared object file".
#
#   sudo scripts/test_addon_portable.sh [ZIP]     (default: the build's zip)
#
# Needs root (debootstrap, chroot, mounts) and Debian's mirror (PM_DEBIAN_MIRROR). The root
# is kept in build/portable/bookworm for the next run (PM_PORTABLE_FRESH=1 rebuilds it).
# Costs (2 cores, bench/RESULTS.md): a fresh root ~4-6 min and ~1 GB, a rerun ~30 s.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD="${PM_BUILD_DIR:-$ROOT/build}"
ZIP="${1:-$(ls "$BUILD"/blender_addon/particlemesh-*-blender-addon.zip 2>/dev/null | head -1)}"
WORK="${PM_PORTABLE_DIR:-$BUILD/portable}"
ROOTFS="$WORK/bookworm"
MIRROR="${PM_DEBIAN_MIRROR:-http://deb.debian.org/debian}"
# Paths inside the bare root (relative to it: "$ROOTFS/$X" from here, "/$X" in the chroot),
# and the host's files the chroot needs.
TEST_DIR="tmp/pm"              # the zip and the check script, inside the root
BLENDER_BIN="usr/bin/blender"  # Debian's blender, inside the root
HOST_RESOLV="${PM_HOST_RESOLV_CONF:-/etc/resolv.conf}"  # name resolution for apt in the root
HOST_DEV="${PM_HOST_DEV:-/dev}"                          # bound into the root for Blender

if [ -z "$ZIP" ] || [ ! -f "$ZIP" ]; then
  echo "test_addon_portable: no add-on zip (build it first: ./scripts/setup.sh)" >&2
  exit 1
fi
if [ "$(id -u)" -ne 0 ]; then
  echo "test_addon_portable: needs root (debootstrap, chroot)" >&2
  exit 1
fi
for tool in debootstrap chroot mount; do
  command -v "$tool" >/dev/null || { echo "test_addon_portable: $tool is missing (apt-get install $tool)" >&2; exit 1; }
done

mounted=()
cleanup() {
  for ((k = ${#mounted[@]} - 1; k >= 0; k--)); do umount -l "${mounted[k]}" 2>/dev/null || true; done
}
trap cleanup EXIT
mount_in() {  # mount_in TYPE-OR---bind SOURCE TARGET
  mkdir -p "$3"
  if [ "$1" = "--bind" ]; then mount --bind "$2" "$3"; else mount -t "$1" "$2" "$3"; fi
  mounted+=("$3")
}

start=$(date +%s)
if [ "${PM_PORTABLE_FRESH:-0}" = 1 ]; then rm -rf "$ROOTFS"; fi
if [ ! -x "$ROOTFS/$BLENDER_BIN" ]; then
  rm -rf "$ROOTFS"
  mkdir -p "$WORK"
  echo "test_addon_portable: debootstrap --variant=minbase bookworm ($MIRROR)"
  debootstrap --variant=minbase bookworm "$ROOTFS" "$MIRROR" >"$WORK/debootstrap.log" 2>&1 ||
    { tail -20 "$WORK/debootstrap.log" >&2; exit 1; }
  t=$(date +%s); echo "test_addon_portable: root made in $((t - start)) s"
  cp "$HOST_RESOLV" "$ROOTFS/etc/resolv.conf"
  mount_in proc proc "$ROOTFS/proc"
  echo "test_addon_portable: apt-get install --no-install-recommends blender python3-numpy"
  chroot "$ROOTFS" env DEBIAN_FRONTEND=noninteractive bash -c \
    "apt-get update -q && apt-get install -y -q --no-install-recommends blender python3-numpy" \
    >"$WORK/apt.log" 2>&1 || { tail -20 "$WORK/apt.log" >&2; exit 1; }
  chroot "$ROOTFS" apt-get clean
  t2=$(date +%s); echo "test_addon_portable: blender installed in $((t2 - t)) s"
  cleanup; mounted=()
fi
echo "test_addon_portable: the root has $(chroot "$ROOTFS" dpkg-query -W -f='${Package}\n' | wc -l) packages," \
     "$(chroot "$ROOTFS" dpkg-query -W -f='${Version}' blender 2>/dev/null | sed 's/^/blender /')"
if compgen -G "$ROOTFS/usr/lib/*/libOpenMeshCore*" >/dev/null; then
  echo "test_addon_portable: the root has OpenMesh: not a fair test" >&2
  exit 1
fi

mount_in proc proc "$ROOTFS/proc"
mount_in --bind "$HOST_DEV" "$ROOTFS/dev"
mkdir -p "$ROOTFS/$TEST_DIR"
cp "$ZIP" "$ROOTFS/$TEST_DIR/addon.zip"
cp "$ROOT/scripts/portable_addon_check.py" "$ROOTFS/$TEST_DIR/"
rc=0
chroot "$ROOTFS" env -i HOME="/$TEST_DIR" PATH="/${BLENDER_BIN%/*}:/bin" LANG=C.UTF-8 \
  blender --background --factory-startup -noaudio --python-exit-code 1 \
  --python "/$TEST_DIR/portable_addon_check.py" -- "/$TEST_DIR/addon.zip" 2>&1 | grep -E "portable check|Error|error" || rc=1
[ "${PIPESTATUS[0]}" -eq 0 ] || rc=1
echo "test_addon_portable: $([ $rc -eq 0 ] && echo passed || echo FAILED) in $(($(date +%s) - start)) s"
exit $rc
