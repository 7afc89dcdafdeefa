#!/usr/bin/env bash
# socat for the DynamixelSDK test (apps.DynamixelSdkSpec): the pseudo-terminal in front of the bus bridge.
set -euo pipefail
command -v socat >/dev/null 2>&1 && exit 0
sudo_() { if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi; }
sudo_ apt-get update -qq
DEBIAN_FRONTEND=noninteractive sudo_ apt-get install -y -qq --no-install-recommends socat
