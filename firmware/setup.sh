#!/usr/bin/env bash
# Installs what the firmware build and its tests need on a Debian machine, and unpacks nanopb's C runtime
# under firmware/build/third_party (never committed). Idempotent: a second run changes nothing.
#
# Everything comes from Debian bookworm's packages, one version each:
#   gcc-arm-none-eabi, libnewlib-arm-none-eabi   the Cortex-M3 compiler and C library (qemu and cm530 ports)
#   qemu-system-arm                              the emulated board (netduino2) of the qemu port
#   nanopb, protobuf-compiler, python3-protobuf  the nanopb 0.4.7 generator (.proto -> .pb.c/.pb.h)
#   source package nanopb (0.4.7)                pb_encode.c, pb_decode.c, pb_common.c: the runtime, same
#                                                version as the generator, built into every image
# The runtime is not in any binary package as C source (libnanopb-dev ships an x86-64 library only), so
# the source package is fetched through a deb-src entry this script adds.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
third_party="$here/build/third_party"
nanopb_version="0.4.7"

sudo_() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }

packages=(gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm nanopb protobuf-compiler python3-protobuf
          dpkg-dev)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done

need_source=0
[ -f "$third_party/nanopb/pb_decode.c" ] || need_source=1

deb_src=/etc/apt/sources.list.d/naogateway-firmware-src.sources
updated=0
if [ "$need_source" = 1 ] && ! grep -rqs '^Types:.*deb-src' /etc/apt/sources.list.d/ && \
   ! grep -qs '^deb-src' /etc/apt/sources.list; then
  # The same mirror apt already uses for the binary packages: from a deb822 file, else from a one-line entry.
  mirror="$(sed -n 's/^URIs: *//p' /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '!/security/ {print $1; exit}')"
  [ -n "$mirror" ] || mirror="$(cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null |
    awk '$1 == "deb" && !/security/ {for (i = 2; i <= NF; i++) if ($i ~ /^[a-z]+:\/\//) {print $i; exit}}')"
  [ -n "$mirror" ] || { echo "setup: no Debian mirror in apt's sources to fetch nanopb's source package from" >&2; exit 1; }
  printf 'Types: deb-src\nURIs: %s\nSuites: bookworm\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' \
    "$mirror" | sudo_ tee "$deb_src" >/dev/null
fi

if [ "${#missing[@]}" -gt 0 ] || [ "$need_source" = 1 ]; then
  sudo_ apt-get update -qq
  updated=1
fi
if [ "${#missing[@]}" -gt 0 ]; then
  DEBIAN_FRONTEND=noninteractive sudo_ apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if [ "$need_source" = 1 ]; then
  [ "$updated" = 1 ] || sudo_ apt-get update -qq
  work="$(mktemp -d)"
  (cd "$work" && apt-get source --download-only -qq "nanopb=${nanopb_version}-2" >/dev/null)
  orig="$(ls "$work"/nanopb_${nanopb_version}*.orig.tar.* | head -1)"
  mkdir -p "$third_party"
  rm -rf "$third_party/nanopb"
  mkdir -p "$third_party/nanopb"
  tar -xf "$orig" -C "$third_party/nanopb" --strip-components=1
  rm -rf "$work"
fi

# The generator Debian ships runs on Debian's own python3 (it needs python3-protobuf).
command -v nanopb_generator.py >/dev/null || { echo "setup: nanopb_generator.py missing" >&2; exit 1; }
echo "firmware setup: ok (nanopb ${nanopb_version} runtime in ${third_party}/nanopb)"
