# Sourced by the container tests (containers_smoke.sh, compose_fleet.sh) after `cd SOURCE_DIR`,
# with BUILD_DIR exported and fail() defined: builds the service images from the host build. Exits
# 77 (ctest skip) only when podman cannot run containers on this machine at all; a missing podman
# or a failed build is a failure.
command -v podman >/dev/null || fail "podman is not installed (scripts/setup installs it)"
if ! out=$(podman info 2>&1); then
  echo "SKIP: podman cannot run here: $(tail -n 3 <<<"$out")"
  exit 77
fi
scripts/containers build || fail "building the images failed"
if ! out=$(podman run --rm --network none localhost/bookworm-min true 2>&1); then
  echo "SKIP: podman cannot start a container here: $(tail -n 3 <<<"$out")"
  exit 77
fi
