//! How a number the user gave is shown back in a message ([`Short`]), without allocating: the
//! core's errors and the runtime's messages print values the same way.

use core::fmt;

/// A number as a message shows it: Rust's shortest round-trip digits, in exponent notation
/// outside 1e-4 ≤ |x| < 1e6 (so `5e-324`, `1e9` and `1e300`, never 300-digit decimals), `NaN`,
/// `inf` and `-inf` as such. (The result files' numbers,
/// `toolconf_files::csv::format_number`, keep decimals up to 1e16 and leave the
/// non-finite out.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Short(pub f64);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0;
        if x.is_nan() {
            f.write_str("NaN")
        } else if x.is_infinite() {
            f.write_str(if x > 0.0 { "inf" } else { "-inf" })
        } else if x == 0.0 {
            f.write_str("0")
        } else if (1e-4..1e6).contains(&x.abs()) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}
