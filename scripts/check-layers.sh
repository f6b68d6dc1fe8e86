#!/usr/bin/env bash
# Enforces the layering (docs/architecture.md): a file in layer L may include combabc headers only
# from L itself and the layers L is declared to depend on, and every declared dependency must come
# earlier in `order`, so no back edge (and no cycle) can be declared either. Like Stan's
# test-math-dependencies: a cheap grep that fails CI. There is no exception list.
#
# A layer may also be split into sub-layers, folders inside its folders (src/<layer>/<sub>/ and
# include/combabc/<layer>/<sub>/), listed lowest first: a file in a sub-layer may include headers
# of its own sub-layer and earlier ones only, and the files directly in the layer's folders sit
# above every sub-layer. Public headers are named from include/ ("combabc/plate/elements/x.hpp"),
# private ones from src/ ("plate/fast_path/x.hpp").
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
  [export]="core samplers metrics history"
  [services]="core rng params proposals distances schedules samplers design simulators plate data metrics config history export"
)
# plate: the element kernels (and the laminate they take) <- the assembled plate (grid,
# constraints, loads, full solves, modes) <- the fast paths (condensations and their solves) <- the
# sensor model at the top (docs/architecture.md).
# services: the adapters (the sensor model as a Simulator, the simulator factory, the Python
# script runner) <- the steps several jobs share (the problem, the run steps, the fingerprint, the
# output folders, the read-back) <- the jobs at the top (run, resume, enumerate, design,
# simulate, report, history tools, model choice).
declare -A sublayers=(
  [plate]="elements assembly fast_path"
  [services]="adapters steps"
)
# Layers whose public top headers (include/combabc/<layer>/*.hpp) every sub-layer may include:
# the services' headers are their interface, the requests, outcomes and types the steps
# implement (ExecutorFactory, StopLimits, RunOutcome); the jobs' private files (src/<layer>/*)
# stay out of the sub-layers' reach.
declare -A public_top=([services]=1)
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
# Sub-layers: every file of a layer with sub-layers lies in one of them or at the layer's top, and
# none includes a header of a later sub-layer or of the top.
declare -A subrank=()
sub_rank() {  # the rank of a path below the layer's folder ("fast_path/x.hpp": fast_path's)
  if [[ "$2" != */* ]]; then echo "top"; else echo "${subrank[$1/${2%%/*}]-none}"; fi
}
for layer in "${!sublayers[@]}"; do
  read -ra subs <<<"${sublayers[$layer]}"
  for i in "${!subs[@]}"; do subrank[$layer/${subs[$i]}]=$i; done
  subrank[$layer/top]=${#subs[@]}
  for f in $(git ls-files "include/combabc/$layer/*" "src/$layer/*"); do
    inner=${f#include/combabc/"$layer"/}
    own=$(sub_rank "$layer" "${inner#src/"$layer"/}")
    if [[ "$own" == none ]]; then
      echo "layering: $f is not in a declared sub-layer of $layer (${sublayers[$layer]})"; status=1
      continue
    fi
    [[ "$own" == top ]] && continue  # the top may include every sub-layer
    for used in $(grep -hoE "#include \"(combabc/)?$layer/[a-z0-9_./]+\"" "$f" |
        sed -E "s|#include \"||; s|\"\$||"); do
      public=0
      [[ "$used" == combabc/* ]] && public=1
      used=${used#combabc/}
      used=${used#"$layer"/}
      rank=$(sub_rank "$layer" "$used")
      [[ "$rank" == top && $public == 1 && -n "${public_top[$layer]-}" ]] && continue
      if [[ "$rank" == top || "$rank" == none || $rank -gt $own ]]; then
        echo "layering: $f ($layer/${subs[$own]}) includes $layer/$used, not a lower sub-layer"
        status=1
      fi
    done
  done
done
[ $status -eq 0 ] && echo "layers: clean"
exit $status
