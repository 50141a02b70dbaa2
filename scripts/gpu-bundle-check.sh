#!/usr/bin/env bash
# Checks a GPU bundle (scripts/gpu-bundle.sh) as a bare machine would see it: unpacks it with
# scripts/gpu-unpack.py, then
#  1. resolves every binary's libraries through the bundle's wrapper: each must come from the
#     bundle or be a library every glibc system has (or the GL driver's, behind libglvnd);
#  2. runs `nestlight demo` (a small one) in a clean environment (`env -i`, the library path
#     only to the bundle) with this machine's copy of every library the bundle carries made
#     unreadable (bind mounts over them in a private mount namespace, where root may make one),
#     so a library the bundle forgot fails the run here instead of on the GPU machine.
#   scripts/gpu-bundle-check.sh [BUNDLE]      (default .gpu/nestlight-gpu-bundle.tar.xz)
set -euo pipefail
cd "$(dirname "$0")/.."
bundle=${1:-.gpu/nestlight-gpu-bundle.tar.xz}
work=$(mktemp -d)
[ -n "${KEEP_CHECK:-}" ] || trap 'rm -rf "$work"' EXIT
b=$(python3 scripts/gpu-unpack.py "$bundle" "$work" | tail -n 1)

# 1. Where each library comes from, through the wrapper's library path.
allowed='^(linux-vdso\.so|ld-linux-x86-64\.so|libc\.so|libm\.so|libdl\.so|libpthread\.so|librt\.so|libresolv\.so|libutil\.so|libstdc\+\+\.so|libgcc_s\.so)'
bad=0
for bin in "$b"/bin/*; do
  while read -r name _ path _; do
    [ -n "$name" ] || continue
    if [ "$path" = "not" ]; then
      echo "gpu-bundle-check: $(basename "$bin"): $name not found" >&2
      bad=1
    elif [[ "$path" != "$b"/* ]] && ! [[ "$name" =~ $allowed ]]; then
      echo "gpu-bundle-check: $(basename "$bin"): $name comes from $path, not from the bundle" >&2
      bad=1
    fi
  done < <(env -i PATH=/usr/bin:/bin LD_LIBRARY_PATH="$b/lib:$b/gl" ldd "$bin" | awk '/=>/ {print $1, $2, $3, $4}')
done
[ "$bad" = 0 ] || exit 1
echo "gpu-bundle-check: every library of $(ls "$b/bin" | wc -l) binaries resolves into the bundle or glibc" >&2

# 2. The demo, with this machine's copies of the bundle's libraries hidden.
hide=()
for f in "$b"/lib/* "$b"/gl/*; do
  name=$(basename "$f")
  for dir in /lib/x86_64-linux-gnu /usr/lib/x86_64-linux-gnu /usr/local/lib /lib /usr/lib; do
    [ -e "$dir/$name" ] && hide+=("$(readlink -f "$dir/$name")")
  done
done
mapfile -t hide < <(printf '%s\n' "${hide[@]}" | sort -u)
cat >"$work/demo.sh" <<EOF
set -e
for f in ${hide[*]}; do mount --bind /dev/null "\$f"; done
cd "$work"
exec env -i PATH=/usr/bin:/bin HOME="$work" "$b/run" nestlight demo -n 200k --no-view --dir "$work/demo" --image "$work/demo.png"
EOF
if [ "$(id -u)" = 0 ] && unshare -m --propagation private true 2>/dev/null; then
  echo "gpu-bundle-check: demo in a clean environment, ${#hide[@]} system copies of bundled libraries hidden" >&2
  unshare -m --propagation private bash "$work/demo.sh"
else
  echo "gpu-bundle-check: demo in a clean environment (no mount namespace here: system copies not hidden)" >&2
  sed -i '/mount --bind/d' "$work/demo.sh"
  bash "$work/demo.sh"
fi
test -s "$work/demo.png"
echo "gpu-bundle-check: OK" >&2
