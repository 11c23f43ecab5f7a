#!/usr/bin/env bash
# Installs the Debian packages tetraprobe needs to build, test and run, skipping what is already there.
# Usage: tools/setup/setup.sh        (run as root, or with sudo available)
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config
  # build side (GPL / AGPL / Apache): only tetra/, bake/, scene/, eval/ and the CLI link these
  libcgal-dev libgmp-dev libmpfr-dev libtet1.5-dev libembree-dev libtbb-dev
  libtinygltf-dev libtinyobjloader-dev libstb-dev libtinyexr-dev nlohmann-json3-dev
  # eval --plot (tools/cli only; LGPL / MPL): cairo draws the chart to SVG and PNG, text in DejaVu Sans
  libcairo2-dev fonts-dejavu-core
  # engine side and rendering (permissive)
  libglm-dev libvulkan-dev mesa-vulkan-drivers vulkan-tools glslang-tools spirv-tools
  # tests and benchmarks
  libgtest-dev libgmock-dev libbenchmark-dev
  # the scale benchmark (bench/scale.py) and the sample generators (samples/*/make_*.py); the scheduler
  # files' test (tests/cli/scheduler_manifests_test.py) parses YAML
  python3 python3-yaml
  # fuzzing (make fuzz): clang 14 and its runtime libraries; libclang_rt.fuzzer is in libclang-rt-14-dev
  clang libclang-rt-14-dev
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "setup: error: need root (or sudo) to install: ${missing[*]}" >&2
    exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
if ! $SUDO apt-get update -qq; then
  echo "setup: error: 'apt-get update' failed; cannot install ${missing[*]}" >&2
  exit 1
fi
if ! $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"; then
  echo "setup: error: 'apt-get install' failed for: ${missing[*]}" >&2
  exit 1
fi
echo "setup: done"
