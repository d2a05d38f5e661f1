#!/usr/bin/env bash
# The σ maps of the paper's Figs. 3, 4, 6, 7 and 8 from a `sflsh validate` folder (its dynamics.vtp), drawn with
# `sflsh render --map` (one colour scale per picture, its top at the 99th percentile of all panels):
#   scripts/validate_figures.sh VALIDATE_DIR [OUT_DIR]      (OUT_DIR defaults to VALIDATE_DIR)
# Writes fig3_truth_vs_independent.png, fig4_leave_one_out.png (when the run cross-validated),
# fig6_full_optimization.png, fig7_covariance.png (when the truth's parameters are known) and
# fig8_generalization.png (when there are test subjects with a truth). SFLSH=path/to/sflsh overrides the binary.
set -euo pipefail
dir=${1:?usage: scripts/validate_figures.sh VALIDATE_DIR [OUT_DIR]}
out=${2:-$dir}
root=$(cd "$(dirname "$0")/.." && pwd)
sflsh=${SFLSH:-$root/build/release/apps/sflsh/sflsh}
vtp=$dir/dynamics.vtp
[[ -f $vtp ]] || { echo "validate_figures: $vtp not found (expected the folder of a sflsh validate run)" >&2; exit 1; }
[[ -x $sflsh ]] || { echo "validate_figures: $sflsh is not an executable (build first, or set SFLSH)" >&2; exit 1; }
mkdir -p "$out"
fields=$(grep -o 'Name="\(sigma\|covariance\)_[^"]*"' "$vtp" | sed 's/^Name="//; s/"$//' | sort -u)
has() { grep -qxF "$1" <<<"$fields"; }
train=$(sed -n 's/^sigma_independent_//p' <<<"$fields")
test_subjects=$(sed -n 's/^sigma_truth_//p' <<<"$fields" | grep -vxF "$train" || true)
# draw FILE PATTERN SUBJECTS…: panels PATTERN (space-separated, @ = subject) per subject, those present only.
draw() {
  local file=$1 pattern=$2 list=() s p f
  shift 2
  for s in "$@"; do
    for p in $pattern; do
      f=${p//@/$s}
      if has "$f"; then list+=("$f"); fi
    done
  done
  [[ ${#list[@]} -gt 0 ]] || return 0
  local IFS=,
  "$sflsh" -q render --map "$vtp" --fields "${list[*]}" --label "${label:-sigma}" --view front --out "$out/$file"
  echo "validate_figures: wrote $out/$file (${#list[@]} panels)"
}
# shellcheck disable=SC2086  # subject lists split on newlines on purpose
draw fig3_truth_vs_independent.png "sigma_truth_@ sigma_independent_@" $train
# shellcheck disable=SC2086
if grep -q '^sigma_cv_' <<<"$fields"; then draw fig4_leave_one_out.png "sigma_independent_@ sigma_cv_l2_@ sigma_cv_ours_@" $train; fi
# shellcheck disable=SC2086
draw fig6_full_optimization.png "sigma_independent_@ sigma_full_l2_@ sigma_full_ours_@" $train
label=covariance draw fig7_covariance.png "covariance_truth covariance_independent covariance_ours covariance_l2" x
# shellcheck disable=SC2086
[[ -z $test_subjects ]] || draw fig8_generalization.png "sigma_truth_@ sigma_full_l2_@ sigma_full_ours_@" $test_subjects
