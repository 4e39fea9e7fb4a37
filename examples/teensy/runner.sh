#!/usr/bin/env bash
# Cargo runner for the Teensy firmware (examples/teensy/.cargo/config.toml):
#
#   cd examples/teensy
#   cargo run --release --target thumbv7em-none-eabihf --features teensy36 --bin teensy-app
#
# 1. finds the board in the ELF: the size of `__INTERRUPTS` (the device vectors that
#    src/rt.rs builds from `Board::irq_count`) is 92 vectors on the MK20DX256 (Teensy
#    3.1/3.2), 86 on the MK64FX512 (3.5) and 100 on the MK66FX1M0 (3.6);
# 2. converts the ELF to Intel HEX with `llvm-objcopy` (the `llvm-tools` rustup component,
#    else an `llvm-objcopy` in PATH, Debian package `llvm`);
# 3. checks the HEX: every record's checksum, an end-of-file record, the flash
#    configuration field at 0x400 (docs/firmware.md), nothing beyond the chip's flash;
# 4. flashes it with `teensy_loader_cli --mcu=TEENSY32|TEENSY35|TEENSY36 -w -v`.
#
# With TWOCAN_RUNNER_DRY_RUN=1 (or --dry-run before the ELF) it stops after step 3 and
# prints the teensy_loader_cli command instead of running it: CI uses this, having no
# board. TEENSY_MCU=TEENSY32|TEENSY35|TEENSY36 overrides step 1.
#
# Exit status: 0 flashed (or dry run passed), 1 a tool is missing or failed, 2 bad input.
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
shift # cargo run -- ARGS: passed to teensy_loader_cli (e.g. -s for a soft reboot)

die() {
    echo "teensy runner: $*" >&2
    exit 1
}

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
    die "$name not found: run \`rustup component add llvm-tools\` (or install Debian's \`llvm\` package)"
}

objcopy=$(llvm_tool llvm-objcopy)
nm=$(llvm_tool llvm-nm)

# 1. The board.
if [ -n "${TEENSY_MCU:-}" ]; then
    mcu=$TEENSY_MCU
else
    size_hex=$("$nm" -S --defined-only "$elf" | awk '$4 == "__INTERRUPTS" { print $2 }')
    [ -n "$size_hex" ] || { echo "teensy runner: $elf has no __INTERRUPTS symbol: not a twocan-teensy firmware? (set TEENSY_MCU)" >&2; exit 2; }
    case $((16#$size_hex / 4)) in
        92) mcu=TEENSY32 ;;
        86) mcu=TEENSY35 ;;
        100) mcu=TEENSY36 ;;
        *) echo "teensy runner: $((16#$size_hex / 4)) device vectors match no Teensy 3.x (set TEENSY_MCU)" >&2; exit 2 ;;
    esac
fi
case $mcu in
    TEENSY32) flash_bytes=$((256 * 1024)) ;; # MK20DX256
    TEENSY35) flash_bytes=$((512 * 1024)) ;; # MK64FX512
    TEENSY36) flash_bytes=$((1024 * 1024)) ;; # MK66FX1M0
    *) echo "teensy runner: TEENSY_MCU=$mcu: expected TEENSY32, TEENSY35 or TEENSY36" >&2; exit 2 ;;
esac

# 2. ELF -> Intel HEX, next to the ELF.
hex="$elf.hex"
"$objcopy" -O ihex "$elf" "$hex" || die "$objcopy -O ihex $elf $hex failed"

# 3. Check the HEX.
check_hex() {
    local line n=0 base=0 eof=0 flash_config=0 top=0 len addr type sum i end
    while IFS= read -r line || [ -n "$line" ]; do
        line=${line%$'\r'}
        n=$((n + 1))
        [[ $line =~ ^:([0-9A-F]{2})+$ ]] || { echo "line $n: not an Intel HEX record" >&2; return 1; }
        [ "$eof" = 0 ] || { echo "line $n: record after the end-of-file record" >&2; return 1; }
        len=$((16#${line:1:2}))
        [ ${#line} -eq $((11 + 2 * len)) ] || { echo "line $n: length does not match its count" >&2; return 1; }
        sum=0
        for ((i = 1; i < ${#line}; i += 2)); do
            sum=$((sum + 16#${line:i:2}))
        done
        [ $((sum & 255)) -eq 0 ] || { echo "line $n: bad checksum" >&2; return 1; }
        addr=$((16#${line:3:4}))
        type=$((16#${line:7:2}))
        case $type in
            0)
                end=$((base + addr + len))
                [ "$end" -le "$top" ] || top=$end
                if [ $((base + addr)) -eq $((16#400)) ]; then
                    [ "$line" = ":10040000FFFFFFFFFFFFFFFFFFFFFFFFFEF9FFFF03" ] || {
                        echo "line $n: the flash configuration field at 0x400 is $line (expected :10040000FFFFFFFFFFFFFFFFFFFFFFFFFEF9FFFF03, docs/firmware.md)" >&2
                        return 1
                    }
                    flash_config=1
                fi
                ;;
            1) eof=1 ;;
            2) base=$((16#${line:9:4} * 16)) ;;
            4) base=$((16#${line:9:4} * 65536)) ;;
            3 | 5) ;;
            *) echo "line $n: unknown record type $type" >&2; return 1 ;;
        esac
    done <"$hex"
    [ "$eof" = 1 ] || { echo "no end-of-file record" >&2; return 1; }
    [ "$flash_config" = 1 ] || { echo "no flash configuration field at 0x400" >&2; return 1; }
    [ "$top" -le "$flash_bytes" ] || {
        echo "data up to 0x$(printf %X "$top"), beyond the $((flash_bytes / 1024)) KiB flash of $mcu" >&2
        return 1
    }
    echo "teensy runner: $hex: $n records, image ends at 0x$(printf %X "$top") of $((flash_bytes / 1024)) KiB, flash configuration field ok"
}
check_hex || { echo "teensy runner: $hex failed its check" >&2; exit 1; }

# 4. Flash.
flash=(teensy_loader_cli "--mcu=$mcu" -w -v "$@" "$hex")
if [ "$dry_run" = 1 ]; then
    echo "teensy runner: dry run, would run: ${flash[*]}"
    exit 0
fi
command -v teensy_loader_cli >/dev/null ||
    die "teensy_loader_cli not found: install Debian's \`teensy-loader-cli\` package (or build it from PJRC's sources); the HEX is $hex"
echo "teensy runner: ${flash[*]}  (press the program button if nothing happens)"
exec "${flash[@]}"
