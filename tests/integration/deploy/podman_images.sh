# Sourced by the container tests (containers_smoke.sh, compose_fleet.sh, container_images.sh) after
# `cd SOURCE_DIR`, with BUILD_DIR exported and fail() defined: builds the service images from the
# host build, unless FLEET_IMAGES_BUILT=1 says they are built already (ctest sets it for the tests
# that need the fixture container_images, whose test built them in this run). Exits 77 (ctest skip)
# only when podman cannot run containers on this machine at all; a missing podman or a failed build
# is a failure.
command -v podman >/dev/null || fail "podman is not installed (scripts/setup installs it)"
if ! out=$(podman info 2>&1); then
  echo "SKIP: podman cannot run here: $(tail -n 3 <<<"$out")"
  exit 77
fi
if [[ ${FLEET_IMAGES_BUILT:-0} != 1 ]]; then
  scripts/containers build || fail "building the images failed"
fi
if ! out=$(podman run --rm --network none localhost/bookworm-min true 2>&1); then
  echo "SKIP: podman cannot start a container here: $(tail -n 3 <<<"$out")"
  exit 77
fi
