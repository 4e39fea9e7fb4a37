// Firmware quick start: CAN1 of an STM32F7 handed over by `stm32f7xx-hal` (feature
// `hal-stm32f7`; the chip is the one the program's HAL dependency selects), on PD0/PD1
// at 500 kbit/s, with no `unsafe`. This file is the crate documentation's firmware
// quick start and, verbatim, part of the workspace test `tests/tests/first_program.rs`.
use stm32f7xx_hal::pac;
use stm32f7xx_hal::prelude::*;
use twocan_bxcan::regs::CanRegs;
use twocan_bxcan::{hal, BxCan, FifoPolicy, Recovery};
use twocan_core::split::State;
use twocan_core::{Error, FifoQueue, Filter};

static CAN1: State<BxCan<CanRegs>, 32, FifoQueue<16>, 32> = State::new();

fn start(dp: pac::Peripherals) -> Result<(), Error> {
    let rcc = dp.RCC.constrain();
    let clocks = rcc.cfgr.sysclk(216.MHz()).pclk1(54.MHz()).freeze();
    let mut apb1 = rcc.apb1;
    let gpiod = dp.GPIOD.split();
    let rx = gpiod.pd0.into_alternate::<9>(); // CAN1_RX is AF9 on PD0
    let tx = gpiod.pd1.into_alternate::<9>(); // CAN1_TX is AF9 on PD1

    // The hand-over: the singleton and the pins by value (another pin, or another
    // alternate function, does not compile); CAN1 is clocked through APB1.
    let can1 = hal::can1(dp.CAN1, tx, rx, &mut apb1, &clocks);
    // Bit timing from the APB1 frequency the HAL set.
    let config = can1
        .config(500_000)
        .map_err(|_| Error::InvalidArgument)?
        .recovery(Recovery::Automatic);
    let mut init = can1.configure(&config)?; // initialization mode, #[must_use]
    let filters = [Filter::standard(0x100), Filter::extended(0x1234_5678)];
    let plan = init.can().plan(&filters, FifoPolicy::Fifo0)?;
    init.set_filters(&plan)?;
    let can = init.enable()?; // on the bus (bounded wait on INAK)
    let parts = CAN1.split(can.into_split()).map_err(|(e, _)| e)?;
    // Move parts.tx_irq / rx0_irq / rx1_irq / status_irq to the vectors CAN1_TX,
    // CAN1_RX0, CAN1_RX1 and CAN1_SCE, then unmask them; parts.tx and parts.rx belong to
    // thread code or tasks.
    let _ = parts;
    Ok(())
}
