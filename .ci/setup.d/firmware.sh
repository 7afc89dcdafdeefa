#!/usr/bin/env bash
# The firmware's tools (ARM compiler, QEMU, nanopb) and nanopb's C runtime, so its specs run instead of cancelling.
set -euo pipefail
bash "$(dirname "${BASH_SOURCE[0]}")/../../firmware/setup.sh"
