#!/bin/sh
# protect_system.sh WRITABLE_DIR... -- CMD [ARGS...]
# Runs CMD with the file-system view systemd gives deploy/systemd/luxeld.service,
# for deploy_sandbox (no systemd starts units on the build machine). Call it
# inside a private mount namespace: unshare -m --propagation private sh protect_system.sh ...
#   ProtectSystem=strict  every mount read-only except the API file systems
#                         and the WRITABLE_DIRs (StateDirectory, CacheDirectory)
#   PrivateTmp=yes        an empty /tmp of its own
#   ProtectHome=yes       /root, /home and /run/user empty and read-only
# WRITABLE_DIRs must not lie under /tmp, /root or /home.
set -eu
writable=""
while [ "$#" -gt 0 ] && [ "$1" != "--" ]; do
  mkdir -p "$1"
  writable="$writable $1"
  shift
done
[ "$#" -gt 1 ] || { echo "usage: protect_system.sh DIR... -- CMD [ARGS...]" >&2; exit 2; }
shift
for d in $writable; do mount --bind "$d" "$d"; done
# Field 5 of mountinfo is the mount point (octal escapes for spaces: such
# mounts stay as they are).
awk '{print $5}' /proc/self/mountinfo | while read -r m; do
  case "$m" in /proc* | /sys* | /dev*) continue ;; esac
  mount -o remount,bind,ro "$m" 2>/dev/null || true
done
for d in $writable; do mount -o remount,bind,rw "$d"; done
mount -t tmpfs -o mode=1777 tmpfs /tmp
for h in /root /home /run/user; do
  if [ -d "$h" ]; then mount -t tmpfs -o ro,mode=0755 tmpfs "$h"; fi
done
exec "$@"
