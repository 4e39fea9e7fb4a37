use twocan_core::Frame;
use twocan_flexcan::acan;

let mut core = cortex_m::Peripherals::take().ok_or("taken")?;
// ACAN: `ACAN::can0.begin (ACANSettings (125 * 1000))`. Here one call: token, ACAN's
// defaults and pins, the library's static state, interrupts wired; the two halves.
let (mut tx, mut rx) = acan::can0(125_000, &mut core.NVIC)?;

// ACAN `tryToSend`: `WouldBlock` while the transmit buffer is full.
let frame = Frame::standard(0x542, &[1, 2])?;
let _token = tx.try_send(&frame);
// ACAN `receive`: every frame (the one call installs a pass-all filter).
while let Ok(received) = rx.receive() {
    let _ = received.frame;
}

// ACAN `end`: the way back; `acan::can0` runs again afterwards.
acan::end_can0((tx, rx), &mut core.NVIC).map_err(|(e, _)| e)?;
# Ok::<(), Box<dyn std::error::Error>>(())
