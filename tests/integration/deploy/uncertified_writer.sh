# Sourced by netns_fleet.sh and compose_fleet.sh, with ctl() (fleetctl against the run's adapter),
# fail() and SECURE defined. check_uncertified_writer WHAT: after a participant without a
# certificate (WHAT) wrote Tasks "rogue-<n>" onto the domain, rogue-0 must reach the manager without
# DDS Security (so the check can fail) and must not with it.
check_uncertified_writer() {
  local what=$1 reached=0
  for _ in $(seq 10); do
    ctl task rogue-0 2>/dev/null | grep -q '"state"' && { reached=1; break; }
    sleep 0.5
  done
  if ((SECURE)); then
    ((reached == 0)) || fail "a Task written by the $what without a certificate reached the manager"
    echo "secure: the fleet ran with DDS Security; no Task of the uncertified $what reached the manager"
  else
    ((reached == 1)) || fail "without security the $what's Task should reach the manager (is the check broken?)"
    echo "without security the uncertified $what's Task reached the manager, as expected"
  fi
}
