#!/usr/bin/env bash
# The two model-choice methods measured against each other on the tiny-sensor model choice of
# tests/e2e/enumerate_test.cpp (docs/benchmarks.md, "Model choice: evidence or joint"): 3 + 3
# clamps, clamped against simply supported, prior 1/2 each, least squares to 4, 3, 2.4. For each
# method and size (accepted per wave), 20 seeds: mean simulations, mean and largest |P - exact|,
# seeds within 0.02, mean z^2 and mean reported se of P(simply supported).
# Usage: [METHODS="evidence joint"] bench/model_choice/methods.sh [combabc binary] [sizes...]
# (default build/apps/combabc and sizes 100 200 400 800)
set -euo pipefail
combabc=$(realpath "${1:-build/apps/combabc}")
shift || true
sizes=("${@:-100 200 400 800}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
{
  echo "position_m,displacement_m"
  for i in $(seq 31 3 59); do
    python3 -c "print(f'{$i/100},{1.0-abs($i/100-0.45)}')"
  done
} > data.csv
config() {  # method size seed
  cat <<TOML
[model.clamps]
per_edge = 3
[model.mesh]
elements_per_section = 2
elements_across_width = 2
[data]
csv = "data.csv"
position_column = "position_m"
displacement_column = "displacement_m"
position_unit = "m"
displacement_unit = "m"
[metric]
threshold = [4.0, 3.0, 2.4]
[[metric.component]]
type = "least_squares"
window = [0.31, 0.58]
[sampler]
waves = 3
accepted_per_wave = $2
seed = $3
[output]
directory = "out"
[model_choice]
method = "$1"
[[model_choice.model]]
name = "clamped"
prior = 0.5
[[model_choice.model]]
name = "pinned"
prior = 0.5
model.clamps.fixed_support = "simply_supported"
TOML
}
config evidence 100 1 > run.toml
"$combabc" enumerate run.toml --no-report -q -o exact > /dev/null
exact=$(awk -F, '$1 == "pinned" {print $3}' exact/model_choice/models.csv)
echo "exact P(pinned) = $exact"
echo "method size simulations mean_abs_err max_abs_err within_0.02 mean_z2 mean_se"
for size in ${sizes[*]}; do
  for method in ${METHODS:-evidence joint}; do
    rows=""
    for seed in $(seq 1 20); do
      config "$method" "$size" "$seed" > run.toml
      rm -rf out
      "$combabc" run run.toml --no-report -q -j 1 > /dev/null
      sims=$(awk -F, 'NR > 1 && $1 != "" {print $12; exit}' out/model_choice/models.csv)
      if [[ $method == evidence ]]; then
        sims=$(awk -F, 'NR > 1 {s += $12} END {print s}' out/model_choice/models.csv)
      fi
      row=$(awk -F, '$1 == "pinned" {print $3, $4}' out/model_choice/models.csv)
      rows+="$sims $row"$'\n'
    done
    printf '%s' "$rows" | awk -v m="$method" -v n="$size" -v x="$exact" '
      NF == 3 { k++; s += $1; e = $2 - x; if (e < 0) e = -e; a += e; if (e > w) w = e;
                if (e <= 0.02) c++; z += e * e / ($3 * $3); se += $3 }
      END { printf "%s %d %.0f %.4f %.4f %d/20 %.2f %.4f\n", m, n, s / k, a / k, w, c, z / k, se / k }'
  done
done
