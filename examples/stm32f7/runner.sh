#!/usr/bin/env bash
# Cargo runner for the STM32 firmware (examples/stm32f7/.cargo/config.toml, and
# examples/stm32/runner.sh, which runs this file):
#
#   cd examples/stm32f7
#   cargo run --release --target thumbv7em-none-eabihf --features nucleo-f767zi,defmt --bin stm32f7-app
#   cd examples/stm32
#   cargo run --release --target thumbv7m-none-eabi --features bluepill,defmt --bin stm32-app
#
# 1. finds the chip in the ELF: the size of `__INTERRUPTS` (the device vectors of the
#    PAC) is 110 vectors on the STM32F767 (NUCLEO-F767ZI: STM32F767ZITx), 98 on the
#    STM32F746 (32F746G-DISCOVERY: STM32F746NGHx), 97 on the STM32F446 (NUCLEO-F446RE:
#    STM32F446RETx) and 60 on the STM32F103 (the stm32f1 PAC's `stm32f103` table; Blue
#    Pill: STM32F103C8);
# 2. says whether probe-rs will show defmt output: the ELF needs a `.defmt` section
#    (`--features defmt`) and the RTT control block `_SEGGER_RTT` (defmt-rtt);
# 3. runs `probe-rs run --chip CHIP ELF`: flashes through the board's ST-LINK, resets, and
#    prints the RTT/defmt output until Ctrl-C.
#
# probe-rs has no dry-run mode. TWOCAN_RUNNER_DRY_RUN=1 (or --dry-run before the ELF) is
# this project's stand-in: steps 1 and 2, then the probe-rs command is printed instead of
# run. CI uses it, having no board. PROBE_RS_CHIP=NAME overrides step 1.
#
# Exit status: probe-rs's when it runs; 0 for a dry run that passed, 1 probe-rs missing,
# 2 bad input.
set -euo pipefail

dry_run=${TWOCAN_RUNNER_DRY_RUN:-0}
if [ "${1:-}" = "--dry-run" ]; then
    dry_run=1
    shift
fi
if [ $# -lt 1 ] || [ ! -f "$1" ]; then
    echo "usage: runner.sh [--dry-run] FIRMWARE.elf  (cargo passes the ELF: see the header)" >&2
    exit 2
fi
elf=$1
shift # cargo run -- ARGS: passed to probe-rs run

# An LLVM binary utility: the llvm-tools component of the active toolchain first.
llvm_tool() {
    local name=$1 sysroot host
    if sysroot=$(rustc --print sysroot 2>/dev/null) && host=$(rustc -vV | sed -n 's/^host: //p'); then
        if [ -x "$sysroot/lib/rustlib/$host/bin/$name" ]; then
            echo "$sysroot/lib/rustlib/$host/bin/$name"
            return
        fi
    fi
    if command -v "$name" >/dev/null; then
        command -v "$name"
        return
    fi
    echo "stm32 runner: $name not found: run \`rustup component add llvm-tools\` (or install Debian's \`llvm\` package)" >&2
    exit 1
}
nm=$(llvm_tool llvm-nm)
readelf=$(llvm_tool llvm-readelf)

# 1. The chip.
if [ -n "${PROBE_RS_CHIP:-}" ]; then
    chip=$PROBE_RS_CHIP
else
    size_hex=$("$nm" -S --defined-only "$elf" | awk '$4 == "__INTERRUPTS" { print $2 }')
    [ -n "$size_hex" ] || { echo "stm32 runner: $elf has no __INTERRUPTS symbol: not a twocan STM32 firmware? (set PROBE_RS_CHIP)" >&2; exit 2; }
    case $((16#$size_hex / 4)) in
        110) chip=STM32F767ZITx ;;
        98) chip=STM32F746NGHx ;;
        97) chip=STM32F446RETx ;;
        60) chip=STM32F103C8 ;;
        *) echo "stm32 runner: $((16#$size_hex / 4)) device vectors: not an STM32F767, F746, F446 or F103 (set PROBE_RS_CHIP)" >&2; exit 2 ;;
    esac
fi

# 2. defmt over RTT.
sections=$("$readelf" -S "$elf")
symbols=$("$nm" --defined-only "$elf")
if grep -q ' \.defmt ' <<<"$sections" && grep -q ' _SEGGER_RTT$' <<<"$symbols"; then
    echo "stm32 runner: $elf: chip $chip, defmt over RTT (probe-rs decodes the log)"
else
    echo "stm32 runner: $elf: chip $chip, no defmt log in this build (add --features defmt to see one)"
fi

# 3. Flash and run.
run=(probe-rs run --chip "$chip" "$@" "$elf")
if [ "$dry_run" = 1 ]; then
    echo "stm32 runner: dry run, would run: ${run[*]}"
    exit 0
fi
command -v probe-rs >/dev/null || {
    echo "stm32 runner: probe-rs not found: install it (\`cargo install probe-rs-tools --locked\`), then connect the board's ST-LINK; the command is: ${run[*]}" >&2
    exit 1
}
exec "${run[@]}"
