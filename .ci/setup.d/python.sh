#!/usr/bin/env bash
# Python 3 with venv for the Python client's and the conformance robot's tests.
set -euo pipefail
python3 -c 'import venv, ensurepip' 2>/dev/null && exit 0
sudo_() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }
sudo_ apt-get update -qq
DEBIAN_FRONTEND=noninteractive sudo_ apt-get install -y -qq --no-install-recommends python3-venv
