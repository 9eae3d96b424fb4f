# Checks shared by the demo mission tests. Source it from bash after defining fail MESSAGE
# (which reports and exits), then:
#   check_ran_without_restart PERF_TXT WHEN PROCESS...
# fails unless the launcher's report PERF_TXT (sarmap-log perf) shows each PROCESS on localhost
# with at least 5 samples and no restart; WHEN ends the restart message (e.g. " under the attack").

check_ran_without_restart() {
  local perf="$1" when="$2"
  shift 2
  local process line samples restarts
  for process in "$@"; do
    line="$(grep "localhost/$process " "$perf" || true)"
    [ -n "$line" ] || fail "$process never reported by the launcher"
    samples="$(echo "$line" | awk '{print $2}')"
    restarts="$(echo "$line" | awk '{print $6}')"
    [ "$samples" -ge 5 ] || fail "$process ran for only $samples launcher samples"
    [ "$restarts" = 0 ] || fail "$process restarted $restarts times$when"
  done
}
