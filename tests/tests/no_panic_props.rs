//! Property tests: random raw values into every public constructor never panic, and the
//! result agrees with the format's rules.

use proptest::prelude::*;
use twocan_core::frame::raw_to_id;
use twocan_core::{Dispatcher, Filter, FilterError, Format, Frame, FrameError, FrameKind, RxFrame};

fn kind(k: u8) -> FrameKind {
    [FrameKind::Data, FrameKind::Remote, FrameKind::Any][k as usize % 3]
}
fn format(f: u8) -> Format {
    [Format::Standard, Format::Extended, Format::Any][f as usize % 3]
}

proptest! {
    #[test]
    fn frame_constructors(raw in any::<u32>(), ext in any::<bool>(), dlc in any::<u8>(),
                          data in proptest::collection::vec(any::<u8>(), 0..16), remote in any::<bool>()) {
        let limit = if ext { 0x1FFF_FFFF } else { 0x7FF };
        let by_id = raw_to_id(raw, ext);
        prop_assert_eq!(by_id.is_ok(), raw <= limit);
        let std = Frame::standard(raw as u16, &data);
        prop_assert_eq!(std.is_ok(), (raw as u16) <= 0x7FF && data.len() <= 8);
        let x = Frame::extended(raw, &data);
        match x {
            Ok(f) => { prop_assert!(raw <= 0x1FFF_FFFF && data.len() <= 8); prop_assert_eq!(f.data(), &data[..]); }
            Err(FrameError::ExtendedIdOutOfRange(r)) => prop_assert_eq!(r, raw),
            Err(FrameError::TooMuchData(n)) => prop_assert_eq!(n, data.len()),
            Err(e) => prop_assert!(false, "unexpected {:?}", e),
        }
        let r = Frame::remote(raw, ext, dlc);
        // One DLC rule (issue 22 item 10): a remote frame takes any code of the field.
        prop_assert_eq!(r.is_ok(), raw <= limit && dlc <= 15);
        let mut bytes = [0u8; 8];
        for (b, d) in bytes.iter_mut().zip(&data) { *b = *d; }
        let reg = Frame::from_registers(raw, ext, remote, dlc, bytes);
        if let Ok(f) = reg {
            prop_assert_eq!(f.dlc(), dlc);
            prop_assert_eq!(f.data().len(), if remote { 0 } else { dlc.min(8) as usize });
            prop_assert_eq!(embedded_can::Frame::dlc(&f), dlc.min(8) as usize);
            prop_assert_eq!(f.raw_id(), raw);
        } else {
            prop_assert!(raw > limit || dlc > 15);
        }
        if let Ok(id) = by_id {
            let w = Frame::with_dlc(id, &data, dlc);
            let fits = data.len() <= 8
                && dlc <= 15
                && (usize::from(dlc) == data.len() || (dlc > 8 && data.len() == 8));
            prop_assert_eq!(w.is_ok(), fits);
            if let Ok(f) = w {
                prop_assert_eq!((f.dlc(), f.data()), (dlc, &data[..]));
            }
        }
        if let Ok(id) = by_id {
            let e = <Frame as embedded_can::Frame>::new(id, &data);
            prop_assert_eq!(e.is_some(), data.len() <= 8);
            let e = <Frame as embedded_can::Frame>::new_remote(id, dlc as usize);
            prop_assert_eq!(e.is_some(), dlc <= 15);
        }
    }

    #[test]
    fn frame_word_views(raw in 0u16..0x800, data in proptest::collection::vec(any::<u8>(), 0..=8),
                        index in any::<usize>(), value in any::<u64>()) {
        let mut f = Frame::standard(raw, &data).unwrap();
        let _ = f.data_u16(index);
        let _ = f.data_u32(index);
        let ok16 = f.set_data_u16(index, value as u16).is_ok();
        prop_assert_eq!(ok16, index < data.len() / 2);
        let ok32 = f.set_data_u32(index, value as u32).is_ok();
        prop_assert_eq!(ok32, index < data.len() / 4);
        prop_assert_eq!(f.set_data_u64(value).is_ok(), data.len() == 8);
        prop_assert_eq!(f.set_byte(index, 1).is_ok(), index < data.len());
    }

    #[test]
    fn filter_constructors(k in any::<u8>(), fm in any::<u8>(), id in any::<u32>(), mask in any::<u32>(), probe in any::<u32>()) {
        let f = Filter::masked(kind(k), format(fm), mask, id);
        let limit = format(fm).id_mask();
        match f.check() {
            Ok(()) => {
                prop_assert!(id <= limit && mask <= limit && id & !mask == 0);
                // A conforming filter matches the identifier it was built around.
                let ext = matches!(format(fm), Format::Extended);
                if let Ok(fr) = Frame::from_registers(id & limit, ext, matches!(kind(k), FrameKind::Remote), 0, [0; 8]) {
                    prop_assert!(f.matches(&fr));
                }
            }
            Err(FilterError::AnyFormatWithIdentifier) => prop_assert!(matches!(format(fm), Format::Any)),
            Err(_) => prop_assert!(id > limit || mask > limit || id & !mask != 0),
        }
        let _ = Filter::exact(kind(k), format(fm), id).check();
        let _ = Filter::standard(id as u16).check();
        let _ = Filter::extended(id).check();
        if let Ok(fr) = Frame::extended(probe & 0x1FFF_FFFF, &[]) { let _ = f.matches(&fr); }
    }

    #[test]
    fn dispatcher_indices(index in any::<usize>(), filter in any::<u16>()) {
        let mut d: Dispatcher<u32, 8> = Dispatcher::new();
        prop_assert_eq!(d.set(index, |c, _| *c += 1).is_ok(), index < 8);
        let rx = RxFrame { frame: Frame::standard(1, &[]).unwrap(), filter, timestamp: None, hw_match: 0 };
        let mut ctx = 0;
        let taken = d.dispatch(&mut ctx, &rx);
        prop_assert_eq!(taken, index < 8 && filter as usize == index);
        prop_assert_eq!(d.handled() + d.unhandled(), 1);
    }
}
