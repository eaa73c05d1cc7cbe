#!/usr/bin/env bash
# Phase timing for scripts/setup.sh and scripts/test.sh (sourced): `phase NAME` records the time
# since the last phase, `timing_summary WHAT` prints them all with the total.
timing_start=$(date +%s)
timing_last=$timing_start
timing_phases=()
phase() {
  local now
  now=$(date +%s)
  timing_phases+=("$1 $((now - timing_last)) s")
  echo "   ($1: $((now - timing_last)) s)"
  timing_last=$now
}
timing_summary() {
  local total=$(($(date +%s) - timing_start)) joined
  joined=$(printf '%s, ' "${timing_phases[@]}")
  echo "$1 took $((total / 60)) min $((total % 60)) s: ${joined%, }"
}
