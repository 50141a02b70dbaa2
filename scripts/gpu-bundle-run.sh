#!/usr/bin/env bash
# `run PROGRAM ARGS...` inside an unpacked GPU bundle (scripts/gpu-bundle.sh): runs bin/PROGRAM
# (nestlight and the GL test suites of scripts/gpu-suites.txt) with the bundle's libraries and GL loaders
# on the library path, and the NVIDIA driver's EGL vendor file where the machine keeps it outside
# libglvnd's default folders.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
if [ $# -lt 1 ] || [ ! -x "$here/bin/$1" ]; then
  echo "usage: $0 PROGRAM [ARGS...]; programs: $(ls "$here/bin" | tr '\n' ' ')" >&2
  exit 2
fi
prog=$1
shift
path="$here/lib:$here/gl"
# libstdc++ and libgcc_s of the build machine, only where this machine's are older.
want=$(cat "$here/glibcxx")
ldconfig=$(command -v ldconfig || echo /sbin/ldconfig)
sys=$("$ldconfig" -p 2>/dev/null | awk '/libstdc\+\+\.so\.6 .*x86-64/ {print $NF; exit}' || true)
if [ -z "$sys" ] || ! grep -qa "$want" "$sys" 2>/dev/null; then path="$path:$here/fallback"; fi
for d in /usr/local/nvidia/lib64 /usr/local/nvidia/lib /usr/lib/x86_64-linux-gnu/nvidia; do
  [ -d "$d" ] && path="$path:$d"
done
if [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ] && [ ! -e /usr/share/glvnd/egl_vendor.d/10_nvidia.json ] &&
  [ ! -e /etc/glvnd/egl_vendor.d/10_nvidia.json ]; then
  for f in /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json /usr/local/share/glvnd/egl_vendor.d/10_nvidia.json; do
    if [ -e "$f" ]; then
      # Naming vendor files replaces libglvnd's search: Mesa's stays listed where it is installed.
      vendors=$f
      [ -e /usr/share/glvnd/egl_vendor.d/50_mesa.json ] && vendors="$vendors:/usr/share/glvnd/egl_vendor.d/50_mesa.json"
      export __EGL_VENDOR_LIBRARY_FILENAMES="$vendors"
      break
    fi
  done
fi
export LD_LIBRARY_PATH="$path${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
exec "$here/bin/$prog" "$@"
