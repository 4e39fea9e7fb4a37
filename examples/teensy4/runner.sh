#!/usr/bin/env bash
# Cargo runner for the Teensy 4 firmware (examples/teensy4/.cargo/config.toml):
#
#   cd examples/teensy4
#   cargo run --release --features teensy41 --bin teensy4-app
#
# 1. finds the board in the ELF: the flash size in the FlexSPI configuration block
#    (`sflashA1Size`, offset 0x50 of the block at 0x6000_0000: 8 MiB on the Teensy 4.1,
#    2 MiB on the 4.0; src/boot.rs);
# 2. converts the ELF to Intel HEX with `llvm-objcopy` (the `llvm-tools` rustup component,
#    else an `llvm-objcopy` in PATH);
# 3. checks the HEX: every record's checksum, an end-of-file record, the configuration
#    block's tag "FCFB" at 0x6000_0000 and the image vector table's header at 0x6000_1000
#    (what the boot ROM reads, docs/firmware.md), nothing beyond the board's flash;
# 4. flashes it with `teensy_loader_cli --mcu=TEENSY40|TEENSY41 -w -v`.
#
# With TWOCAN_RUNNER_DRY_RUN=1 (or --dry-run before the ELF) it stops after step 3 and
# prints the teensy_loader_cli command instead. TEENSY_MCU=TEENSY40|TEENSY41 overrides
# step 1.
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
shift

die() {
    echo "teensy4 runner: $*" >&2
    exit 1
}

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

# 1. The board, from the configuration block.
boot=$(mktemp)
trap 'rm -f "$boot"' EXIT
"$objcopy" -O binary --only-section=.boot "$elf" "$boot" ||
    { echo "teensy4 runner: $elf has no .boot section: not a twocan-teensy4 firmware?" >&2; exit 2; }
size=$(od -An -tu4 -j $((16#50)) -N4 "$boot" | tr -d ' ')
if [ -n "${TEENSY_MCU:-}" ]; then
    mcu=$TEENSY_MCU
else
    case $size in
        $((8 << 20))) mcu=TEENSY41 ;;
        $((2 << 20))) mcu=TEENSY40 ;;
        *) echo "teensy4 runner: flash size $size in the configuration block matches no Teensy 4 (set TEENSY_MCU)" >&2; exit 2 ;;
    esac
fi
case $mcu in
    TEENSY41) flash_bytes=$((8 << 20)) ;;
    TEENSY40) flash_bytes=$((2 << 20)) ;;
    *) echo "teensy4 runner: TEENSY_MCU=$mcu: expected TEENSY40 or TEENSY41" >&2; exit 2 ;;
esac

# 2. ELF -> Intel HEX, next to the ELF.
hex="$elf.hex"
"$objcopy" -O ihex "$elf" "$hex" || die "$objcopy -O ihex $elf $hex failed"

# 3. Check the HEX.
check_hex() {
    local line n=0 base=0 eof=0 fcb=0 ivt=0 top=0 len addr type sum i end flash=$((16#60000000))
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
                [ $((base + addr)) -ne "$flash" ] || [ "${line:9:8}" != 46434642 ] || fcb=1
                [ $((base + addr)) -ne $((flash + 16#1000)) ] || [ "${line:9:8}" != D1002040 ] || ivt=1
                ;;
            1) eof=1 ;;
            2) base=$((16#${line:9:4} * 16)) ;;
            4) base=$((16#${line:9:4} * 65536)) ;;
            3 | 5) ;;
            *) echo "line $n: unknown record type $type" >&2; return 1 ;;
        esac
    done <"$hex"
    [ "$eof" = 1 ] || { echo "no end-of-file record" >&2; return 1; }
    [ "$fcb" = 1 ] || { echo "no FlexSPI configuration block (tag FCFB) at 0x60000000" >&2; return 1; }
    [ "$ivt" = 1 ] || { echo "no image vector table header at 0x60001000" >&2; return 1; }
    [ "$top" -le $((flash + flash_bytes)) ] || {
        echo "data up to 0x$(printf %X "$top"), beyond the $((flash_bytes >> 20)) MiB flash of $mcu" >&2
        return 1
    }
    echo "teensy4 runner: $hex: $n records, image ends at 0x$(printf %X "$top"), boot header ok"
}
check_hex || { echo "teensy4 runner: $hex failed its check" >&2; exit 1; }

# 4. Flash.
flash_cmd=(teensy_loader_cli "--mcu=$mcu" -w -v "$@" "$hex")
if [ "$dry_run" = 1 ]; then
    echo "teensy4 runner: dry run, would run: ${flash_cmd[*]}"
    exit 0
fi
command -v teensy_loader_cli >/dev/null ||
    die "teensy_loader_cli not found: install Debian's \`teensy-loader-cli\` package; the HEX is $hex"
echo "teensy4 runner: ${flash_cmd[*]}  (press the program button if nothing happens)"
exec "${flash_cmd[@]}"
