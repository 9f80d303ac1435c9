//! Mirrored subtrees of a model: two sibling subtrees with the same joints, axes and geometry
//! below their first joint (Krang's two arms), whose inputs pair up one to one — each body's
//! inertial parameters with the mirrored body's, each joint's speed with the mirrored joint's.
//! The lowering uses the pairing to compute the two subtrees' statements in two lanes
//! (`lower::lanes`, "arms in lanes").

use kanegen_model::{JointKind, Link, Model};

/// The pairing of a model's mirrored subtrees: involutions on parameters and speeds (a
/// parameter or speed outside the subtrees, or shared by both, maps to itself) and the pairs
/// of frames.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Mirror {
    /// `params[i]`: the parameter in the other subtree's place of parameter `i`.
    pub params: Vec<usize>,
    /// `speeds[s]`: the speed of the mirrored joint of speed `s`.
    pub speeds: Vec<usize>,
    /// The paired frames' names, first subtree first.
    pub frames: Vec<(String, String)>,
}

/// The pairing while it is built: `None` where nothing is paired yet.
struct Building {
    params: Vec<Option<usize>>,
    speeds: Vec<Option<usize>>,
    frames: Vec<(usize, usize)>,
}

impl Building {
    /// Pair `a` with `b` in `map` (both ways); false if either is paired otherwise.
    fn pair(map: &mut [Option<usize>], a: usize, b: usize) -> bool {
        match (map[a], map[b]) {
            (None, None) => {
                map[a] = Some(b);
                map[b] = Some(a);
                true
            }
            (x, y) => x == Some(b) && y == Some(a),
        }
    }

    /// Whether subtree `a` mirrors subtree `b` (recording the pairs): at the subtrees' roots
    /// the joints' placements may differ, below they must be the same up to paired
    /// parameters.
    fn subtree(&mut self, model: &Model, a: usize, b: usize, root: bool) -> bool {
        let (la, lb): (&Link, &Link) = (&model.links[a], &model.links[b]);
        let (Some(ma), Some(mb)) = (&la.mount, &lb.mount) else {
            return false;
        };
        let (ja, jb) = (&ma.joint, &mb.joint);
        let same_kind = match (ja.kind, jb.kind) {
            (JointKind::Revolute { speed: x }, JointKind::Revolute { speed: y })
            | (JointKind::Prismatic { speed: x }, JointKind::Prismatic { speed: y }) => {
                Self::pair(&mut self.speeds, x, y)
            }
            (JointKind::Fixed, JointKind::Fixed) => true,
            _ => false,
        };
        if !same_kind || ja.axis != jb.axis {
            return false;
        }
        if !root {
            if ja.rotation != jb.rotation {
                return false;
            }
            for (x, y) in ja.translation.iter().zip(&jb.translation) {
                let ok = x.coef == y.coef
                    && match (x.symbol, y.symbol) {
                        (None, None) => true,
                        (Some(p), Some(q)) => Self::pair(&mut self.params, p, q),
                        _ => false,
                    };
                if !ok {
                    return false;
                }
            }
        }
        match (&la.body, &lb.body) {
            (Some(x), Some(y)) => {
                let xs = [x.mass].into_iter().chain(x.first_moment).chain(x.inertia);
                let ys = [y.mass].into_iter().chain(y.first_moment).chain(y.inertia);
                for (p, q) in xs.zip(ys) {
                    if !Self::pair(&mut self.params, p, q) {
                        return false;
                    }
                }
            }
            (None, None) => {}
            _ => return false,
        }
        let (ca, cb) = (model.children(a), model.children(b));
        if ca.len() != cb.len() {
            return false;
        }
        self.frames.push((a, b));
        ca.iter()
            .zip(&cb)
            .all(|(&x, &y)| self.subtree(model, x, y, false))
    }
}

impl Mirror {
    /// The mirrored sibling subtrees of `model` (the first mirror of each subtree, searched
    /// from the root; subtrees inside a paired one are not paired again), or `None` when it
    /// has none. Models with mimic joints have none (a dependent joint's angle is formed from
    /// its master's, which the pairing does not follow).
    pub fn of(model: &Model) -> Option<Mirror> {
        if !model.mimics.is_empty() {
            return None;
        }
        let mut b = Building {
            params: vec![None; model.params.len()],
            speeds: vec![None; model.speeds.len()],
            frames: Vec::new(),
        };
        let mut inside = vec![false; model.links.len()];
        for parent in 0..model.links.len() {
            if inside[parent] {
                continue;
            }
            let children = model.children(parent);
            for (k, &x) in children.iter().enumerate() {
                if inside[x] {
                    continue;
                }
                for &y in &children[k + 1..] {
                    if inside[y] {
                        continue;
                    }
                    let mut trial = Building {
                        params: b.params.clone(),
                        speeds: b.speeds.clone(),
                        frames: Vec::new(),
                    };
                    if trial.subtree(model, x, y, true) && !trial.frames.is_empty() {
                        for &(l, r) in &trial.frames {
                            inside[l] = true;
                            inside[r] = true;
                        }
                        b.params = trial.params;
                        b.speeds = trial.speeds;
                        b.frames.extend(trial.frames);
                        break;
                    }
                }
            }
        }
        // A pair of subtrees without a speed has nothing to compute in lanes.
        if b.speeds.iter().all(Option::is_none) {
            return None;
        }
        let name = |l: usize| model.links[l].name.clone();
        Some(Mirror {
            params: b
                .params
                .iter()
                .enumerate()
                .map(|(i, p)| p.unwrap_or(i))
                .collect(),
            speeds: b
                .speeds
                .iter()
                .enumerate()
                .map(|(i, s)| s.unwrap_or(i))
                .collect(),
            frames: b.frames.iter().map(|&(l, r)| (name(l), name(r))).collect(),
        })
    }

    /// A substitution variable's label with every frame name of one subtree (as the end of a
    /// word: `wd4l`, `MSC10r`, `4l`) replaced by its mirror's (`wd4r`, `MSC10l`, `4r`): the
    /// label of the mirrored quantity, when the derivation names both alike.
    pub fn label(&self, label: &str) -> String {
        let mut out = String::with_capacity(label.len());
        let mut word = String::new();
        let flush = |word: &mut String, out: &mut String| {
            let best = self
                .frames
                .iter()
                .flat_map(|(l, r)| [(l, r), (r, l)])
                .filter(|(from, _)| word.ends_with(from.as_str()))
                .max_by_key(|(from, _)| from.len());
            match best {
                Some((from, to)) => {
                    out.push_str(&word[..word.len() - from.len()]);
                    out.push_str(to);
                }
                None => out.push_str(word),
            }
            word.clear();
        };
        for c in label.chars() {
            if c.is_ascii_alphanumeric() || c == '_' {
                word.push(c);
            } else {
                flush(&mut word, &mut out);
                out.push(c);
            }
        }
        flush(&mut word, &mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn model(file: &str) -> Model {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        Model::from_toml_file(root.join(file)).expect("model loads")
    }

    #[test]
    fn krang_arms_mirror_each_other_with_their_own_inertias_and_shared_lengths() {
        let m = model("models/krang.toml");
        let mirror = Mirror::of(&m).expect("Krang's arms are mirrored");
        let p = |n: &str| m.param_index(n).expect("parameter exists");
        assert_eq!(mirror.params[p("MX10l")], p("MX10r"));
        assert_eq!(mirror.params[p("MX10r")], p("MX10l"));
        assert_eq!(mirror.params[p("L8")], p("L8"));
        assert_eq!(mirror.params[p("MX3")], p("MX3"));
        // Speeds 5..=11 (left arm) and 12..=18 (right arm).
        assert_eq!(mirror.speeds[5], 12);
        assert_eq!(mirror.speeds[18], 11);
        assert_eq!(mirror.speeds[4], 4);
        // Seven arm links and the hand frames.
        assert_eq!(mirror.frames.len(), 8);
        assert_eq!(mirror.label("N(M col 10r) at 9r.x"), "N(M col 10l) at 9l.x");
        assert_eq!(mirror.label("w3 in 4l|ud=0,g=0.x"), "w3 in 4r|ud=0,g=0.x");
        assert_eq!(mirror.label("wd3.y"), "wd3.y");
    }

    #[test]
    fn a_single_chain_has_no_mirror() {
        assert_eq!(Mirror::of(&model("models/two-link.toml")), None);
    }
}
