//! What the model-error tests share: a small valid description and its mutations.

/// Two revolute links on a fixed base frame (the shape of the fixed-wheels report (Zafar 2014), Appendix B). Both bodies have
/// m = 2, S = [0, 0.1, 0] and I_G = diag(0.03, 0.01, 0.03), so J = diag(0.05, 0.01, 0.05).
pub const VALID: &str = include_str!("../data/two_link.toml");

/// `VALID` with each `(from, to)` applied; every `from` must occur exactly once (no silent no-ops).
pub fn mutate(edits: &[(&str, &str)]) -> String {
    let mut text = VALID.to_owned();
    for (from, to) in edits {
        assert_eq!(
            text.matches(from).count(),
            1,
            "mutation pattern {from:?} must occur exactly once"
        );
        text = text.replacen(from, to, 1);
    }
    text
}
