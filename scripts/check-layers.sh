#!/usr/bin/env bash
# Enforces the layering (docs/architecture.md): a file in layer L may include combabc headers only
# from L itself and the layers L is declared to depend on, and every declared dependency must come
# earlier in `order`, so no back edge (and no cycle) can be declared either. Like Stan's
# test-math-dependencies: a cheap grep that fails CI. There is no exception list.
set -euo pipefail
cd "$(dirname "$0")/.."
order=(core mpi rng params schedules proposals distances samplers design simulators plate data metrics
  config history export services)
declare -A deps=(
  [core]=""
  [mpi]="core"
  [rng]="core"
  [params]="core rng"
  [proposals]="core rng params schedules"
  [distances]="core rng"
  [schedules]="core"
  [samplers]="core rng params proposals distances schedules"
  [design]="core rng"
  [simulators]="core rng params samplers"
  [plate]="core"
  [data]="core"
  [metrics]="core distances schedules"
  [config]="core rng params proposals distances schedules samplers simulators plate data metrics"
  [history]="core rng params proposals distances schedules samplers"
  [export]="core history"
  [services]="core rng params proposals distances schedules samplers design simulators plate data metrics config history export"
)
status=0
declare -A rank=()
for i in "${!order[@]}"; do rank[${order[$i]}]=$i; done
for layer in "${order[@]}"; do
  for dep in ${deps[$layer]}; do
    if [[ -z "${rank[$dep]+x}" || ${rank[$dep]} -ge ${rank[$layer]} ]]; then
      echo "layering: $layer declares a dependency on $dep, which is not a lower layer"; status=1
    fi
  done
done
# Every folder under include/combabc and src must be a declared layer (src/internal excepted).
for dir in $(git ls-files include/combabc src | awk -F/ '$1 == "src" && NF > 2 {print $1 "/" $2}
    $1 == "include" && NF > 3 {print $1 "/" $2 "/" $3}' | sort -u); do
  name=$(basename "$dir")
  [[ "$name" == internal ]] && continue
  if [[ -z "${rank[$name]+x}" ]]; then echo "layering: $dir is not a declared layer"; status=1; fi
done
for layer in "${order[@]}"; do
  for f in $(git ls-files "include/combabc/$layer/*" "src/$layer/*" 2>/dev/null); do
    for used in $(grep -ho '#include "combabc/[a-z_]*/' "$f" | sed 's|.*combabc/||; s|/||' | sort -u); do
      if [[ " $layer ${deps[$layer]} " != *" $used "* ]]; then
        echo "layering: $f ($layer) includes combabc/$used/"; status=1
      fi
    done
  done
done
[ $status -eq 0 ] && echo "layers: clean"
exit $status
