#!/usr/bin/env bash
# Enforces the layering (docs/architecture.md): a file in layer L may include combabc headers only
# from the layers L depends on. Like Stan's test-math-dependencies, a cheap grep that fails CI.
set -euo pipefail
cd "$(dirname "$0")/.."
declare -A allowed=(
  [core]="core"
  [rng]="core rng"
  [params]="core rng params"
  [proposals]="core rng params proposals"
  [distances]="core rng distances"
  [schedules]="core schedules"
  [samplers]="core rng params proposals distances schedules samplers"
  [plate]="core plate"
  [io]="core rng params proposals distances schedules samplers plate io metrics"
  [metrics]="core rng params distances schedules samplers plate metrics io"
  [services]="core rng params proposals distances schedules samplers plate io metrics services"
)
status=0
for layer in "${!allowed[@]}"; do
  for f in $(git ls-files "include/combabc/$layer/*" "src/$layer/*" 2>/dev/null); do
    for used in $(grep -ho '#include "combabc/[a-z_]*/' "$f" | sed 's|.*combabc/||; s|/||' | sort -u); do
      if [[ " ${allowed[$layer]} " != *" $used "* ]]; then
        echo "layering: $f ($layer) includes combabc/$used/"; status=1
      fi
    done
  done
done
[ $status -eq 0 ] && echo "layers: clean"
exit $status
