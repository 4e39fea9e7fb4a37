#!/usr/bin/env bash
# Measures the safety net: plants each realistic driver bug of tests/planted/*.patch, one
# at a time, in a temporary git worktree of a base revision (never in the working tree),
# runs the host suites and the firmware-in-the-loop suite with time limits, and prints
# which suite caught it (a failure, or a hang cut by the time limit). docs/testing.md
# holds the measured table.
#
#   bash tests/planted/run.sh [--base REV] [--no-fil] [--no-host] [--doctests] [NAME ...]
#
# NAME: a patch's name without `.patch` (or a prefix such as `05`); all by default.
# --base: the revision patched (default: HEAD of this clone). The worktree lives under
# target/planted/ and is removed at the end; CARGO_TARGET_DIR for its builds is
# target/planted/target (PLANT_TARGET overrides; PLANT_SHARE=1 shares the clone's own
# target folders, see below), so that the first run builds the dependencies once and
# every later one rebuilds only what a patch touches.
#
# Per bug, host: every test binary of `cargo test --workspace`, of twocan-bxcan with
# `model`, of twocan-flexcan with `model,rt,teensy36` and of twocan-core with
# `async,mock` (PLANT_WORKSPACE_ONLY=1: the first only), each run on its own under
# `timeout` (PLANT_TEST_TIMEOUT s, default 120);
# with --doctests, the doctests of the four library crates too (PLANT_DOC_TIMEOUT,
# default 600 s per crate). FIL: the firmware of the family a patch touches is rebuilt
# (can-core: both), the other family's ELFs are the base's, and the whole FIL suite runs
# under `timeout` (PLANT_FIL_TIMEOUT, default 900 s).
#
# Output: one line per bug (host: failing binaries / tests, hung binaries; FIL: failing
# tests or HANG), and the details in target/planted/<name>.log.
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
repo="$(git -C "$here" rev-parse --show-toplevel)"
base=HEAD
fil=1
host=1
doctests=0
names=()
while [ $# -gt 0 ]; do
    case "$1" in
    --base) base="$2"; shift 2 ;;
    --no-fil) fil=0; shift ;;
    --no-host) host=0; shift ;;
    --doctests) doctests=1; shift ;;
    -h | --help) sed -n '2,25p' "$0"; exit 0 ;;
    *) names+=("$1"); shift ;;
    esac
done
work="$repo/target/planted"
tree="$work/tree"
# Cargo names the artifacts of workspace crates by their path relative to the
# workspace: builds of the patched copy in the clone's own target folders replace the
# clone's artifacts while the copy exists. PLANT_SHARE=1 shares them all the same (no
# dependency rebuilt: much faster) — build nothing in the clone during the run; the
# clone's workspace crates are cleaned at the end so that its next build redoes them.
share="${PLANT_SHARE:-0}"
if [ "$share" = 1 ]; then
    export CARGO_TARGET_DIR="$repo/target"
    fil_target="$repo/fil/target"
else
    export CARGO_TARGET_DIR="${PLANT_TARGET:-$work/target}"
    fil_target="$CARGO_TARGET_DIR"
    case "$(realpath -m "$CARGO_TARGET_DIR")" in
    "$(realpath -m "$repo/target")" | "$(realpath -m "$repo/fil/target")")
        echo "PLANT_TARGET must not be the clone's own target folder (PLANT_SHARE=1 does that)" >&2
        exit 2
        ;;
    esac
fi
test_timeout="${PLANT_TEST_TIMEOUT:-120}"
doc_timeout="${PLANT_DOC_TIMEOUT:-600}"
fil_timeout="${PLANT_FIL_TIMEOUT:-900}"
mkdir -p "$work"
rev="$(git -C "$repo" rev-parse --verify "$base^{commit}")" || exit 2

patches=()
for p in "$here"/*.patch; do
    n="$(basename "$p" .patch)"
    if [ ${#names[@]} -eq 0 ]; then
        patches+=("$p")
    else
        for want in "${names[@]}"; do
            case "$n" in "$want"*) patches+=("$p") ;; esac
        done
    fi
done
[ ${#patches[@]} -gt 0 ] || { echo "no patch matches ${names[*]}" >&2; exit 2; }

cleanup() {
    git -C "$repo" worktree remove --force "$tree" >/dev/null 2>&1 || rm -rf "$tree"
    git -C "$repo" worktree prune
    if [ "$share" = 1 ] && [ "${1:-}" = final ]; then
        for p in twocan-core twocan-sim twocan-bxcan twocan-flexcan twocan-app twocan-host \
            twocan-tests twocan-teensy twocan-stm32f7; do
            (cd "$repo" && cargo clean -q -p "$p" 2>/dev/null)
            (cd "$repo" && CARGO_TARGET_DIR="$fil_target" cargo clean -q \
                --manifest-path fil/Cargo.toml -p "$p" 2>/dev/null)
        done
    fi
}
trap 'cleanup final' EXIT
cleanup
git -C "$repo" worktree add --detach -q "$tree" "$rev" || exit 2

# Resets the worktree to the base revision.
reset_tree() {
    git -C "$tree" checkout -q --detach -f "$rev" && git -C "$tree" clean -qfdx -e target
}

# The test executables of one `cargo test` configuration, built (stdout: one path a line).
test_bins() {
    (cd "$tree" && cargo test --no-run --message-format=json "$@" 2>>"$log") |
        python3 -c '
import json, sys
for line in sys.stdin:
    try:
        m = json.loads(line)
    except ValueError:
        continue
    if m.get("reason") == "compiler-artifact" and m.get("executable") and m["profile"]["test"]:
        print(m["executable"])
'
}

# Host suites: "caught" when a binary fails or hangs.
run_host() {
    local failed=0 hung=0 tests=0 bins=0 names_failed=() names_hung=()
    local configs=("--workspace" "-p twocan-bxcan --features model"
        "-p twocan-flexcan --features model,rt,teensy36" "-p twocan-core --features async,mock")
    # PLANT_WORKSPACE_ONLY=1: `cargo test --workspace` alone (its feature unification
    # already turns on the backends' `model` features and the core's `async,mock`: about
    # half the build time on a busy machine).
    [ "${PLANT_WORKSPACE_ONLY:-0}" = 1 ] && configs=("--workspace")
    for cfg in "${configs[@]}"; do
        # shellcheck disable=SC2086 # the package and its features are separate words
        mapfile -t exes < <(test_bins $cfg)
        if [ ${#exes[@]} -eq 0 ]; then
            echo "build failed: cargo test $cfg" >>"$log"
            names_failed+=("build($cfg)")
            failed=$((failed + 1))
            continue
        fi
        for exe in "${exes[@]}"; do
            bins=$((bins + 1))
            local out rc
            out="$(cd "$tree" && timeout "$test_timeout" "$exe" 2>&1)"
            rc=$?
            local short
            short="$(basename "$exe" | sed 's/-[0-9a-f]*$//')"
            if [ $rc -eq 124 ]; then
                hung=$((hung + 1))
                names_hung+=("$short")
                echo "HANG ($test_timeout s): $exe" >>"$log"
            elif [ $rc -ne 0 ]; then
                failed=$((failed + 1))
                local n
                n="$(grep -cE '^test .* FAILED$' <<<"$out")"
                tests=$((tests + n))
                names_failed+=("$short($n)")
                { echo "FAIL: $exe"; grep -E '^test .* FAILED$|panicked at' <<<"$out" | head -20; } >>"$log"
            fi
        done
    done
    if [ "$doctests" = 1 ]; then
        for args in "-p twocan-core --features async,mock" "-p twocan-sim" \
            "-p twocan-bxcan --features model" "-p twocan-flexcan --features model,teensy36"; do
            local out rc
            # shellcheck disable=SC2086
            out="$(cd "$tree" && timeout "$doc_timeout" cargo test --doc $args 2>&1)"
            rc=$?
            if [ $rc -eq 124 ]; then
                hung=$((hung + 1))
                names_hung+=("doc(${args%% --*})")
            elif [ $rc -ne 0 ]; then
                failed=$((failed + 1))
                names_failed+=("doc(${args%% --*})")
                grep -E '^test .* FAILED$' <<<"$out" | head -20 >>"$log"
            fi
        done
    fi
    host_result="$bins binaries: $failed failing (${tests} tests) ${names_failed[*]:-}; $hung hung ${names_hung[*]:-}"
    host_caught=$((failed + hung))
    host_hung=$hung
}

# FIL: the touched family's firmware rebuilt into a copy of the base's ELFs.
base_elf="$work/elf-base"
build_elf() {
    local out="$1" families="$2"
    (cd "$tree" && FIL_ELF_OUT="$out" FIL_FAMILIES="$families" bash fil/build-firmware.sh) >>"$log" 2>&1
}
run_fil() {
    local name="$1" families
    families=""
    grep -q '^+++ b/\(flexcan\|can-core\)/' "$patch" && families="$families teensy"
    grep -q '^+++ b/\(bxcan\|can-core\)/' "$patch" && families="$families stm32"
    local elf="$work/elf-$name"
    rm -rf "$elf"
    cp -r "$base_elf" "$elf"
    if ! build_elf "$elf" "$families"; then
        fil_result="firmware build failed"
        fil_caught=1
        return
    fi
    local out rc
    out="$(cd "$tree" && FIL_ELF_DIR="$elf" FIL_REQUIRE_ELF=1 CARGO_TARGET_DIR="$fil_target" \
        timeout "$fil_timeout" cargo test --release --manifest-path fil/Cargo.toml --no-fail-fast 2>&1)"
    rc=$?
    rm -rf "$elf"
    local failing
    failing="$(grep -E '^test .* FAILED$' <<<"$out" | sed -E 's/^test (.*) \.\.\. FAILED$/\1/')"
    { echo "FIL rc=$rc"; echo "$failing"; grep -E 'panicked at' -A2 <<<"$out" | head -40; } >>"$log"
    local n
    n="$(grep -c . <<<"$failing")"
    if [ $rc -eq 124 ]; then
        fil_result="HANG (cut at $fil_timeout s), $n failing before"
        fil_caught=$((n + 1))
    else
        fil_result="$n failing: $(tr '\n' ' ' <<<"$failing")"
        fil_caught=$n
    fi
}

if [ "$fil" = 1 ]; then
    log="$work/base.log"
    : >"$log"
    reset_tree
    echo "building the base's firmware once ($rev)"
    rm -rf "$base_elf"
    if ! build_elf "$base_elf" "teensy stm32 negative"; then
        echo "the base's firmware does not build: see $log" >&2
        exit 1
    fi
fi

printf '\n%-40s | %-8s | %s\n' "planted bug" "caught" "details"
for patch in "${patches[@]}"; do
    name="$(basename "$patch" .patch)"
    log="$work/$name.log"
    : >"$log"
    reset_tree
    if ! git -C "$tree" apply "$patch" 2>>"$log"; then
        printf '%-40s | %-8s | %s\n' "$name" "n/a" "patch does not apply to $rev"
        continue
    fi
    start=$SECONDS
    host_result="not run"
    host_caught=0
    host_hung=0
    fil_result="not run"
    fil_caught=0
    [ "$host" = 1 ] && run_host
    [ "$fil" = 1 ] && run_fil "$name"
    verdict="MISSED"
    if [ $host_caught -gt 0 ] || [ $fil_caught -gt 0 ]; then verdict="caught"; fi
    printf '%-40s | %-8s | host: %s | FIL: %s | %d s\n' "$name" "$verdict" "$host_result" \
        "$fil_result" $((SECONDS - start))
done
reset_tree
