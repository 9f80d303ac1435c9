//! How generated code names what comes from the model: identifiers, accelerations, sines and
//! cosines of coordinates, the wrapper type. Shared by the expression printer of
//! [`expr`](crate::expr) (listings) and by [`emit`](crate::emit) (Rust source), so that a
//! listing and the generated code use the same names.

/// A model name as a Rust identifier: the one sanitiser of the workspace,
/// [`kanegen_model::sanitize_identifier`] (keywords are made raw identifiers by the emitter).
pub fn identifier(name: &str) -> String {
    kanegen_model::sanitize_identifier(name)
}

/// Name of the acceleration of a speed: `qd_imu` → `qdd_imu`, `xd` → `xdd`, `psid` → `psidd`.
pub fn accel(speed: &str) -> String {
    match speed.strip_prefix("qd") {
        Some(rest) => format!("qdd{rest}"),
        None => format!("{speed}d"),
    }
}

/// Name of the sine of a coordinate: `q_imu` → `s_q_imu`.
pub fn sin(coordinate: &str) -> String {
    format!("s_{coordinate}")
}

/// Name of the cosine of a coordinate: `q_imu` → `c_q_imu`.
pub fn cos(coordinate: &str) -> String {
    format!("c_{coordinate}")
}

/// The wrapper type of a model: `krang-fixed-wheels` → `KrangFixedWheels` (`Model…` if the
/// name does not start with a letter).
pub fn type_name(model: &str) -> String {
    let mut out = String::new();
    let mut up = true;
    for ch in model.chars() {
        if ch.is_ascii_alphanumeric() {
            if up {
                out.extend(ch.to_uppercase());
            } else {
                out.push(ch);
            }
            up = false;
        } else {
            up = true;
        }
    }
    if out.is_empty() || out.starts_with(|c: char| c.is_ascii_digit()) {
        out.insert_str(0, "Model");
    }
    out
}
