#!/usr/bin/env bash
# The service images of the container tests, built once per ctest run (ctest fixture
# container_images, CMakeLists.txt): containers_smoke, compose_fleet, compose_fleet_secure,
# kube_play and kube_play_postgres all use the same image tags, and each rebuilt them (~23 s with
# podman's layer cache, more under load) before ctest ran them with FLEET_IMAGES_BUILT=1. Run by hand
# (without that variable) each of those tests still builds the images itself. Exit 77 (ctest skip)
# only when podman cannot run containers here. Usage: container_images.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
SRC=$1
export BUILD_DIR=$2
cd "$SRC" || exit 1
t0=$SECONDS
fail() { echo "FAIL: $*"; exit 1; }
unset FLEET_IMAGES_BUILT
# shellcheck source=podman_images.sh
source "$(dirname "${BASH_SOURCE[0]}")/podman_images.sh"
echo "PASS: images built in $((SECONDS - t0)) s"
