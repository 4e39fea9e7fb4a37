#!/usr/bin/env bash
# The examples of the STM32F1/F4 HAL hand-over (`twocan_bxcan::hal::f1` and its
# connectivity-line part, `hal::f4`) and of the Teensy 4 hand-over with `teensy4-bsp`
# (`twocan_flexcan::imxrt::ral`),
# cross-built: rustdoc cannot run them (their HALs turn on cortex-m's
# `critical-section-single-core`, which cannot share a host build with the tests'
# `critical-section/std`), so each example is fenced ```ignore for rustdoc and this
# script is its test runner instead:
#
# - every ```ignore block of the module's documentation is extracted as rustdoc would
#   (hidden `# ` lines kept), wrapped in a function and compiled as the library of
#   `twocan-hal-doctests` for the family's target, with its HAL and chip;
# - a block without `compile_fail` must build;
# - a block fenced ```ignore,compile_fail,E0277 must fail, every error must carry that
#   code, and each must name a pin trait of the hand-over (`TxPin`, `RxPin`, `CanPins`):
#   a wrong pin or a wrong alternate function is refused by the pin traits, not by a
#   typo in the example. The Teensy 4 hand-over takes its pads as types
#   (`RalCan::Tx`/`Rx`): a wrong pad is E0308 and the error must say which types
#   differ (`expected ... found ...` on a pad, `Pad<`).
#
# Only the one-file library is rebuilt per example: the dependencies are those of
# `cargo build --target ... -p twocan-bxcan --features hal-stm32f4,...` (same target
# directory), so the whole run takes seconds once they are built.
#
# Usage: bash tools/hal-doctests/run.sh
set -euo pipefail
cd "$(dirname "$0")/../.."

target_dir=${CARGO_TARGET_DIR:-target}
work="$target_dir/hal-doctests"
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)

# module file, target, feature of twocan-hal-doctests, what a refusal must name (in its
# headline, or for E0308 in its `expected`/`found` note)
specs=(
    "bxcan/src/hal/f4.rs thumbv7em-none-eabihf f4 TxPin|RxPin|CanPins"
    "bxcan/src/hal/f1.rs thumbv7m-none-eabi f1 TxPin|RxPin|CanPins"
    "bxcan/src/hal/f1_connectivity.rs thumbv7m-none-eabi f107 TxPin|RxPin|CanPins"
    "flexcan/src/imxrt/ral.rs thumbv7em-none-eabihf t4bsp Pad<"
)

failures=0
total=0
for spec in "${specs[@]}"; do
    read -r module target feature pin_traits <<<"$spec"
    stem=$(basename "$module" .rs)
    # Each block: `$work/<stem>-<n>.rs` (the example in `pub fn doctest`) and a line
    # `<n> <first line> <fence attributes>` in `$work/<stem>.list`.
    awk -v dir="$work" -v stem="$stem" '
        function strip(line) {
            sub(/^[ \t]*\/\/! ?/, "", line)
            return line
        }
        /^[ \t]*\/\/!/ {
            text = strip($0)
            if (!inside && text ~ /^```ignore/) {
                inside = 1
                n++
                out = sprintf("%s/%s-%d.rs", dir, stem, n)
                attrs = substr(text, 4)
                printf "%d %d %s\n", n, NR, attrs > (dir "/" stem ".list")
                printf "// %s example %d (line %d): %s\npub fn doctest() {\n", FILENAME, n, NR, attrs > out
                next
            }
            if (inside && text ~ /^```/) {
                inside = 0
                print "}" > out
                close(out)
                next
            }
            if (inside) {
                # rustdoc hides `# ` lines and a lone `#`; they are still compiled.
                if (text ~ /^# / || text == "#") {
                    text = substr(text, 3)
                }
                print text > out
            }
        }
    ' "$module"
    list="$work/$stem.list"
    if [ ! -s "$list" ]; then
        echo "error: no \`\`\`ignore example found in $module" >&2
        exit 1
    fi
    builds=0
    refused=0
    while read -r n line attrs; do
        total=$((total + 1))
        file="$work/$stem-$n.rs"
        where="$module:$line (example $n, $attrs)"
        log="$work/$stem-$n.log"
        status=0
        TWOCAN_HAL_DOCTEST="$file" cargo build --target "$target" -p twocan-hal-doctests \
            --features "$feature" --color never </dev/null >"$log" 2>&1 || status=$?
        if [[ ",$attrs," != *",compile_fail,"* ]]; then
            if [ "$status" -ne 0 ]; then
                echo "FAIL $where: does not build" >&2
                grep -E '^(error|warning)' -A12 "$log" >&2 || cat "$log" >&2
                failures=$((failures + 1))
            else
                echo "ok   $where: builds"
                builds=$((builds + 1))
            fi
            continue
        fi
        codes=$(tr ',' '\n' <<<"$attrs" | grep -E '^E[0-9]{4}$' || true)
        headlines=$(grep -E '^error(\[E[0-9]{4}\])?: ' "$log" |
            grep -vE '^error: (could not compile|aborting due to)' || true)
        problem=""
        if [ "$status" -eq 0 ]; then
            problem="builds, but must not"
        elif [ -z "$codes" ]; then
            problem="compile_fail without an error code in its fence"
        elif [ -z "$headlines" ]; then
            problem="the build failed without a compiler error"
        else
            while IFS= read -r h; do
                code=$(sed -nE 's/^error\[(E[0-9]{4})\].*/\1/p' <<<"$h")
                if [ -z "$code" ] || ! grep -qx "$code" <<<"$codes"; then
                    problem="an error other than ${codes//$'\n'/ }: $h"
                    break
                fi
                if ! grep -qE "$pin_traits" <<<"$h" &&
                    { [ "$code" != E0308 ] || ! grep -qE "(expected|found).*($pin_traits)" "$log"; }; then
                    problem="an error that names no pin trait or pad ($pin_traits): $h"
                    break
                fi
            done <<<"$headlines"
        fi
        if [ -n "$problem" ]; then
            echo "FAIL $where: $problem" >&2
            cat "$log" >&2
            failures=$((failures + 1))
        else
            echo "ok   $where: refused: $(head -n 1 <<<"$headlines")"
            refused=$((refused + 1))
        fi
    done <"$list"
    echo "$module: $builds built, $refused refused as expected"
    if [ "$builds" -eq 0 ] || [ "$refused" -eq 0 ]; then
        echo "error: $module needs at least one example that builds and one compile_fail" >&2
        failures=$((failures + 1))
    fi
done
if [ "$failures" -ne 0 ]; then
    echo "hal doctests: $failures of $total failed" >&2
    exit 1
fi
echo "hal doctests: $total passed"
