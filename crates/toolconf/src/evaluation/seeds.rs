//! Sub-seeds: one master seed names a whole run, and every random stream of it (a tool sample's
//! trials, a bootstrap) is derived from the master and a label, so that each is independent of
//! the others and of the order they run in.

/// The sub-seed of `label` under `master`: SplitMix64's finaliser applied to
/// `master XOR FNV-1a-64(label)`. Labels are `"<experiment>/<stream>"`, e.g. `"fig2/tools"`.
pub fn derive_seed(master: u64, label: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in label.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    let mut z = (master ^ h).wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}
