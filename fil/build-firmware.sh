#!/usr/bin/env bash
# Builds what the firmware-in-the-loop tests run: every example firmware of every board
# (copied to fil/target/elf/<board>/, since the three Teensy boards share ELF names) and
# the negative-test firmwares of fil/firmware. Run from anywhere.
#
# FIL_ELF_OUT: another output folder (tests/planted/run.sh; the tests read it through
# FIL_ELF_DIR). FIL_FAMILIES: the families to build, among `teensy stm32 negative`
# (default: all). CARGO_TARGET_DIR is honoured.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
out="${FIL_ELF_OUT:-fil/target/elf}"
families=" ${FIL_FAMILIES:-teensy stm32 negative} "
has() { [[ "$families" == *" $1 "* ]]; }
mkdir -p "$out"
target=thumbv7em-none-eabihf
tdir="${CARGO_TARGET_DIR:-target}"
rel="$tdir/$target/release"
# fil/firmware is a workspace of its own: its target folder unless CARGO_TARGET_DIR.
fw_rel="${CARGO_TARGET_DIR:-fil/firmware/target}/$target/release"
has teensy && for board in teensy32 teensy35 teensy36; do
    cargo build --quiet --release --target "$target" -p twocan-teensy --features "$board" --bins
    mkdir -p "$out/$board"
    for bin in loopback loopback-lean filters app async-echo can0-can1; do
        if [ -f "$rel/teensy-$bin" ] && { [ "$bin" != can0-can1 ] || [ "$board" = teensy36 ]; }; then
            cp "$rel/teensy-$bin" "$out/$board/"
        fi
    done
done
has stm32 && for board in nucleo-f767zi disco-f746g; do
    cargo build --quiet --release --target "$target" -p twocan-stm32f7 --features "$board" --bins
    mkdir -p "$out/$board"
    for bin in loopback loopback-lean filters app async-echo can1-can2; do
        if [ -f "$rel/stm32f7-$bin" ] && { [ "$bin" != can1-can2 ] || [ "$board" = nucleo-f767zi ]; }; then
            cp "$rel/stm32f7-$bin" "$out/$board/"
        fi
    done
done
# The Blue Pill (Cortex-M3) and the NUCLEO-F446RE from one source (examples/stm32),
# each built once for its core; can1-can2 on the NUCLEO only.
has stm32 && for spec in bluepill:thumbv7m-none-eabi nucleo-f446re:thumbv7em-none-eabihf; do
    IFS=: read -r board tgt <<<"$spec"
    cargo build --quiet --release --target "$tgt" -p twocan-stm32 --features "$board" --bins
    mkdir -p "$out/$board"
    for bin in loopback loopback-lean filters app async-echo can1-can2; do
        if [ -f "$tdir/$tgt/release/stm32-$bin" ] && { [ "$bin" != can1-can2 ] || [ "$board" = nucleo-f446re ]; }; then
            cp "$tdir/$tgt/release/stm32-$bin" "$out/$board/"
        fi
    done
done
# The Blue Pill `app` at 250 kbit/s (feature bus-250k): the board at the wrong bit rate
# of fil/tests/stm32_family.rs.
if has stm32; then
    cargo build --quiet --release --target thumbv7m-none-eabi -p twocan-stm32 \
        --features bluepill,bus-250k --bin stm32-app
    cp "$tdir/thumbv7m-none-eabi/release/stm32-app" "$out/bluepill/stm32-app-250k"
fi
# The defmt variants (the examples log through defmt-rtt; tests/defmt.rs decodes the log):
# one board of each family, saved as <example>-defmt. DEFMT_LOG is read at compile time
# (the examples' .cargo/config.toml sets it when cargo runs in their folders only).
for spec in twocan-teensy:teensy36:teensy twocan-stm32f7:nucleo-f767zi:stm32f7; do
    IFS=: read -r pkg board prefix <<<"$spec"
    has "$prefix" || { [ "$prefix" = stm32f7 ] && has stm32; } || continue
    DEFMT_LOG=info cargo build --quiet --release --target "$target" -p "$pkg" \
        --features "$board,defmt" --bin "$prefix-app" --bin "$prefix-loopback"
    for bin in app loopback; do
        cp "$rel/$prefix-$bin" "$out/$board/$prefix-$bin-defmt"
    done
done
# The board at the wrong bit rate (tests/negative.rs): the NUCLEO-F767ZI `app` at
# 250 kbit/s (feature bus-250k) on the Teensy `app`'s 500 kbit/s bus.
if has stm32; then
    cargo build --quiet --release --target "$target" -p twocan-stm32f7 \
        --features nucleo-f767zi,bus-250k --bin stm32f7-app
    cp "$rel/stm32f7-app" "$out/nucleo-f767zi/stm32f7-app-250k"
fi
if has negative; then
    cargo build --quiet --release --target "$target" --manifest-path fil/firmware/Cargo.toml
    mkdir -p "$out/negative"
    for bin in kinetis-gate kinetis-stuck kinetis-storm kinetis-hang kinetis-no-wdog core-check stm32-gate stm32-stuck \
        imxrt-boot imxrt-gate imxrt-stuck imxrt-no-can-clock; do
        cp "$fw_rel/$bin" "$out/negative/"
    done
    # The board-profile test programs (raw registers, no twocan API): the NUCLEO-F446RE's
    # (Cortex-M4F, the build above) and the Blue Pill's, built for the Cortex-M3.
    mkdir -p "$out/nucleo-f446re" "$out/bluepill"
    cp "$fw_rel/nucleo-f446re-can" "$out/nucleo-f446re/"
    m3=thumbv7m-none-eabi
    cargo build --quiet --release --target "$m3" --manifest-path fil/firmware/Cargo.toml \
        --bin bluepill-can --bin bluepill-gate --bin bluepill-stuck
    for bin in bluepill-can bluepill-gate bluepill-stuck; do
        cp "${CARGO_TARGET_DIR:-fil/firmware/target}/$m3/release/$bin" "$out/bluepill/"
    done
fi
if has teensy; then
    # Teensy 4.1 (i.MX RT1062, examples/teensy4, issue 24) for the teensy41 profile; its own
    # test firmwares are the imxrt-* above. (The Teensy 4.0 build differs in the flash size
    # of its boot header only; CI cross-builds it.)
    for board in teensy41; do
        cargo build --quiet --release --target "$target" -p twocan-teensy4 --features "$board" --bins
        mkdir -p "$out/$board"
        for bin in loopback loopback-lean filters app async-echo can1-can2; do
            cp "$rel/teensy4-$bin" "$out/$board/"
        done
    done
    # The Teensy 4.1 `app` as node 3 (feature app-node3): the third board of the three-board
    # run (tests/teensy41_examples.rs).
    cargo build --quiet --release --target "$target" -p twocan-teensy4 --features teensy41,app-node3 \
        --bin teensy4-app
    cp "$rel/teensy4-app" "$out/teensy41/teensy4-app-node3"
fi
echo "firmware for the harness in $out ($families)"
