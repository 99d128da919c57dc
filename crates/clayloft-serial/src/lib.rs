//! The printer link (SPEC §9), without Bevy: every G-code line reaches the printer exactly once
//! and in order, whatever the line does to it.
//!
//! - [`line`]: what is sent — comments and blank lines stripped, `N<n> cmd*<xor>`, length limit;
//! - [`reply`]: what the printer says, parsed (`ok` in all its forms, `Resend`, `busy`, `start`,
//!   `Error:`, temperatures);
//! - [`sender`]: the host protocol as a sans-I/O state machine (replies and clock in, bytes and
//!   events out): history ring, resends, keep-alives, timeouts with M105 probing, reset
//!   detection, pause/resume/cancel/emergency stop;
//! - [`fake`]: a Marlin-like printer as a state machine, with fault injection, for tests and for
//!   teaching;
//! - [`link`]: the I/O — the sender over a serial port, the fake printer over a pseudo-terminal.

pub mod fake;
pub mod line;
pub mod link;
pub mod reply;
pub mod sender;

pub use sender::{Event, Sender, SenderConfig};
