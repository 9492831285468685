#!/usr/bin/env bash
# Every file Facet writes goes through one atomic writer (core/util/atomic_write.h): on a full
# disk a write fails with the reason and leaves the old file whole, and a symlinked target
# stays a link. This test runs the command line's writers (solve -o, export: the model and the
# cameras, render -o) on a small tmpfs filled to the last byte, then through a symlink on one
# with room.
#
#   full_disk_test.sh FACET_EXE SAMPLE_DIR
#
# The tmpfs is mounted in a private mount namespace (unshare: as root, or as an unprivileged
# user through a user namespace), so it disappears with the test and needs no cleanup. A
# machine that allows neither fails the test, naming why; it is not skipped.
set -euo pipefail
exe="$1"
sample="$2"

if [ "${FACET_FULL_DISK_INSIDE:-0}" != 1 ]; then
  export FACET_FULL_DISK_INSIDE=1
  if [ "$(id -u)" = 0 ]; then
    exec unshare --mount --propagation private bash "$0" "$@"
  else
    exec unshare --map-root-user --mount --propagation private bash "$0" "$@"
  fi
fi

fail() { echo "FAIL: $*" >&2; exit 1; }
work="$(mktemp -d "${TMPDIR:-/tmp}/facet-full-disk.XXXXXX")"
trap 'cd /; umount "$work/disk" "$work/room" 2>/dev/null; rm -rf "$work"' EXIT
keep="$work/keep"    # reference copies, outside the full disk
disk="$work/disk"    # the small tmpfs
room="$work/room"    # a tmpfs with room, for the symlink case
mkdir -p "$keep" "$disk" "$room"
mount -t tmpfs -o size=2m tmpfs "$disk" || fail "cannot mount a tmpfs (needs root or user namespaces)"
mount -t tmpfs -o size=8m tmpfs "$room" || fail "cannot mount a tmpfs (needs root or user namespaces)"

cp "$sample/leuven.facet" "$sample/leuvenA.jpg" "$disk/"
# Old outputs the failed writes must leave as they are.
printf 'an earlier screenshot\n' >"$disk/shot.png"
printf 'an earlier export\n' >"$disk/model.glb"
printf 'earlier cameras\n' >"$disk/transforms.json"
mkdir "$disk/colmap"
printf 'earlier cameras\n' >"$disk/colmap/cameras.txt"
cp -r "$disk"/* "$keep/"

# Fill the disk to the last block (dd stops at ENOSPC), then the last bytes of a partial block.
dd if=/dev/zero of="$disk/filler" bs=64k 2>/dev/null || true
dd if=/dev/zero of="$disk/filler2" bs=1 2>/dev/null || true
[ "$(df --output=avail "$disk" | tail -1 | tr -d ' ')" = 0 ] || fail "the tmpfs is not full"
before="$(ls -A "$disk" | sort)"

expect_refused() {  # NAME FILE COMMAND...: the command fails, says why, leaves FILE whole
  local name="$1" file="$2"
  shift 2
  local rc=0
  "$@" >"$work/$name.out" 2>"$work/$name.err" || rc=$?
  [ "$rc" != 0 ] || fail "$name: exit 0 on a full disk"
  grep -q "No space left on device" "$work/$name.err" ||
    fail "$name: the message does not say why: $(head -c 400 "$work/$name.err")"
  cmp -s "$disk/$file" "$keep/$file" || fail "$name: $file was changed"
  echo "ok: $name refused ($(grep -m1 'No space' "$work/$name.err" | head -c 160))"
}

cd "$disk"
expect_refused solve leuven.facet "$exe" solve leuven.facet -o leuven.facet
expect_refused export model.glb "$exe" export leuven.facet -o model.glb
expect_refused export-transforms transforms.json "$exe" export leuven.facet -o transforms.json
expect_refused export-colmap colmap/cameras.txt "$exe" export leuven.facet -o colmap/
expect_refused render shot.png "$exe" render leuven.facet -o shot.png --size 320x200
after="$(ls -A "$disk" | sort)"
[ "$before" = "$after" ] || fail "files were left behind: $(diff <(echo "$before") <(echo "$after") | tr '\n' ' ')"
echo "ok: no temporary file left on the full disk"

# A symlinked target: the write replaces the file the link points to, and the link stays.
cp "$keep/leuven.facet" "$keep/leuvenA.jpg" "$room/"
mkdir "$room/real"
printf 'old\n' >"$room/real/shot.png"
cp "$room/leuven.facet" "$room/real/project.facet"
ln -s real/shot.png "$room/shot.png"
ln -s real/project.facet "$room/project.facet"
cd "$room"
"$exe" render leuven.facet -o shot.png --size 320x200 >/dev/null
"$exe" solve project.facet -o project.facet >/dev/null
[ -L shot.png ] && [ -L project.facet ] || fail "a symlinked target was replaced by a file"
[ "$(head -c 4 real/shot.png | od -An -tx1 | tr -d ' ')" = 89504e47 ] || fail "the link's target is not the new PNG"
grep -q '"format"' real/project.facet || fail "the link's target is not a project"
echo "ok: symlinked targets written through, links kept"
