#!/usr/bin/env bash
# Cargo runner of examples/stm32 (.cargo/config.toml): the STM32 runner of
# examples/stm32f7, which finds the chip in the ELF (STM32F103C8 for the Blue Pill,
# STM32F446RETx for the NUCLEO-F446RE) and runs `probe-rs run --chip CHIP`
# (TWOCAN_RUNNER_DRY_RUN=1: prints the command instead).
exec "$(dirname "$0")/../stm32f7/runner.sh" "$@"
