//! Dispatch of received frames to call-backs chosen by filter index (ACAN §14).
//!
//! Each filter of the user's list may have a call-back. [`Dispatcher::dispatch`] hands one
//! received frame to the call-back of the filter that accepted it, after the optional
//! match hook (ACAN's `dispatchReceivedMessage (matchingFunction)`), and reports whether a
//! frame was there. A frame whose filter has no call-back is not silently lost: it is
//! counted ([`Dispatcher::unhandled`]).
//!
//! Call-backs are plain function pointers taking a context `&mut Ctx` (the application's
//! state), so they work in interrupt-free thread code without allocation.

use crate::frame::RxFrame;

/// A call-back for frames accepted by one filter.
pub type Callback<Ctx> = fn(&mut Ctx, &RxFrame);

/// A hook called with the filter index of every dispatched frame, before its call-back.
pub type MatchHook<Ctx> = fn(&mut Ctx, u16);

/// Call-backs for up to `N` filters.
///
/// ```
/// use twocan_core::dispatch::NoSuchFilter;
/// use twocan_core::mock::MockHardware;
/// use twocan_core::{Dispatcher, FifoQueue, Filter, Frame, RxFrame, State};
///
/// #[derive(Default)]
/// struct App { speed: u16, hooked: u32 }
///
/// static CAN: State<MockHardware, 8, FifoQueue<4>> = State::new();
/// // Filter 0 takes 0x100, filter 1 takes 0x200 (the index is the list position).
/// let hw = MockHardware::new(3).with_filters(&[Filter::standard(0x100), Filter::standard(0x200)]);
/// let mut p = CAN.split(hw).map_err(|(e, _)| e)?;
///
/// let mut table: Dispatcher<App, 2> = Dispatcher::new()
///     .with(0, |app: &mut App, rx: &RxFrame| app.speed = rx.frame.data_u16(0).unwrap_or(0))
///     .expect("index 0 is in the table");
/// table.set_match_hook(Some(|app: &mut App, _filter| app.hooked += 1));
/// // An index beyond the table is refused with the index, not ignored.
/// assert_eq!(table.set(2, |_, _| {}), Err(NoSuchFilter(2)));
///
/// CAN.hardware().unwrap().deliver(Frame::standard(0x100, &[0x34, 0x12])?);
/// CAN.hardware().unwrap().deliver(Frame::standard(0x200, &[])?); // filter 1: no call-back
/// p.rx0_irq.on_interrupt();
///
/// let mut app = App::default();
/// while p.rx.dispatch(&mut table, &mut app) {}
/// assert_eq!((app.speed, app.hooked), (0x1234, 2));
/// // The frame without a call-back is counted, not lost silently.
/// assert_eq!((table.handled(), table.unhandled()), (1, 1));
/// # Ok::<(), twocan_core::Error>(())
/// ```
pub struct Dispatcher<Ctx, const N: usize> {
    callbacks: [Option<Callback<Ctx>>; N],
    hook: Option<MatchHook<Ctx>>,
    handled: u32,
    unhandled: u32,
}

impl<Ctx, const N: usize> Default for Dispatcher<Ctx, N> {
    fn default() -> Self {
        Self::new()
    }
}

/// A filter index beyond the dispatcher's table.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NoSuchFilter(pub usize);

impl core::fmt::Display for NoSuchFilter {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "no filter with index {} in the dispatcher", self.0)
    }
}

impl core::error::Error for NoSuchFilter {}

impl<Ctx, const N: usize> Dispatcher<Ctx, N> {
    /// A table with no call-backs.
    pub const fn new() -> Self {
        Dispatcher {
            callbacks: [None; N],
            hook: None,
            handled: 0,
            unhandled: 0,
        }
    }

    /// Attaches `callback` to filter `index` (the position of the filter in the list given
    /// to the backend), replacing any earlier one.
    pub fn set(&mut self, index: usize, callback: Callback<Ctx>) -> Result<(), NoSuchFilter> {
        let slot = self.callbacks.get_mut(index).ok_or(NoSuchFilter(index))?;
        *slot = Some(callback);
        Ok(())
    }

    /// Builder form of [`Dispatcher::set`].
    pub fn with(mut self, index: usize, callback: Callback<Ctx>) -> Result<Self, NoSuchFilter> {
        self.set(index, callback)?;
        Ok(self)
    }

    /// Removes the call-back of filter `index`.
    pub fn clear(&mut self, index: usize) -> Result<(), NoSuchFilter> {
        let slot = self.callbacks.get_mut(index).ok_or(NoSuchFilter(index))?;
        *slot = None;
        Ok(())
    }

    /// Sets the match hook.
    pub fn set_match_hook(&mut self, hook: Option<MatchHook<Ctx>>) {
        self.hook = hook;
    }

    /// Hands `frame` to its filter's call-back (after the match hook). Returns whether a
    /// call-back took it; if not, it is counted in [`Dispatcher::unhandled`].
    pub fn dispatch(&mut self, ctx: &mut Ctx, frame: &RxFrame) -> bool {
        if let Some(hook) = self.hook {
            hook(ctx, frame.filter);
        }
        match self.callbacks.get(frame.filter as usize).copied().flatten() {
            Some(cb) => {
                cb(ctx, frame);
                self.handled = self.handled.saturating_add(1);
                true
            }
            None => {
                self.unhandled = self.unhandled.saturating_add(1);
                false
            }
        }
    }

    /// Frames handed to a call-back.
    pub const fn handled(&self) -> u32 {
        self.handled
    }

    /// Frames whose filter had no call-back (or whose index was beyond the table).
    pub const fn unhandled(&self) -> u32 {
        self.unhandled
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Frame;

    #[test]
    fn no_such_filter_displays_its_index() {
        let e: &dyn core::error::Error = &NoSuchFilter(7);
        assert_eq!(e.to_string(), "no filter with index 7 in the dispatcher");
    }

    #[derive(Default)]
    struct Ctx {
        a: u32,
        b: u32,
        hooks: u32,
    }

    #[test]
    fn dispatch_by_filter_index() {
        let mut d: Dispatcher<Ctx, 3> = Dispatcher::new();
        d.set(0, |c, _| c.a += 1).unwrap();
        d.set(2, |c, f| c.b += f.frame.dlc() as u32).unwrap();
        assert_eq!(d.set(3, |_, _| ()), Err(NoSuchFilter(3)));
        d.set_match_hook(Some(|c, _| c.hooks += 1));
        let mut ctx = Ctx::default();
        let rx = |filter| RxFrame {
            frame: Frame::standard(1, &[1, 2]).unwrap(),
            filter,
            timestamp: None,
            hw_match: 0,
        };
        assert!(d.dispatch(&mut ctx, &rx(0)));
        assert!(d.dispatch(&mut ctx, &rx(2)));
        assert!(!d.dispatch(&mut ctx, &rx(1)));
        assert!(!d.dispatch(&mut ctx, &rx(40)));
        assert_eq!((ctx.a, ctx.b, ctx.hooks), (1, 2, 4));
        assert_eq!((d.handled(), d.unhandled()), (2, 2));
        d.clear(0).unwrap();
        assert!(!d.dispatch(&mut ctx, &rx(0)));
    }
}
