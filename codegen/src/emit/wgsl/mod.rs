//! WGSL compute kernels from the lowered programs: the GPU form of a generated module
//! ([`crate::Builder::gpu`]).
//!
//! The same straight-line programs as the Rust functions, printed as WGSL: one compute entry
//! point per lowered registry function (one state per invocation), each state's inputs and
//! results in structure-of-arrays storage buffers (entry `k` of state `i` at
//! `k · stride + i`), the parameters and the precomputed parameter-only values in read-only
//! storage buffers, the batch size and stride in a uniform buffer. Every kernel exists in `f32`
//! and in `f64` (for adapters with `SHADER_F64`); sines and cosines are computed once per
//! state by the runtime's own polynomial ([`print::sin_cos_fn`]): no `sin`/`cos` built-in,
//! whose `f64` forms some Vulkan drivers evaluate to garbage. Modules with the mass matrix and
//! the velocity and gravity terms also get `forward_dynamics` (an unrolled Cholesky solve,
//! `solve.rs`) and `rollout` (semi-implicit Euler on the device). Deterministic: same
//! programs, same text.
//!
//! Files: `print.rs` (literals, expressions, statement lists, `sin_cos`), `solve.rs` (the
//! unrolled Cholesky solve), `kernel.rs` (bindings, state, entry points), and this file (the
//! kernels' layout and the Rust items of the generated module).

mod kernel;
mod print;
mod solve;

use std::fmt::Write as _;

use crate::lower::Lowered;
use crate::registry::{FunctionSet, Inputs};
use kanegen_model::Model;
use kernel::{Entry, Source};
use print::{Float, Mimic};

pub use kernel::WORKGROUP_SIZE;

/// The GPU kernels of a module: the WGSL source in both float types and each entry point's
/// layout.
#[derive(Clone, Debug, PartialEq)]
pub struct Kernels {
    /// The `f32` module.
    pub wgsl_f32: String,
    /// The `f64` module (needs `SHADER_F64`).
    pub wgsl_f64: String,
    /// Per kernel (lowered registry function): entry point name, inputs, dense result rows and columns.
    pub entries: Vec<(String, Inputs, usize, usize)>,
    /// Whether the module has `forward_dynamics` and `rollout`.
    pub forward_dynamics: bool,
    /// Number of speeds.
    pub dof: usize,
    /// Number of parameters the kernels read (0 with baked parameters).
    pub params: usize,
    /// Number of precomputed values.
    pub precomputed: usize,
}

/// A constant of the programs is not a finite `f32` (the `f32` kernels cannot hold it).
#[derive(Debug, thiserror::Error)]
#[error(
    "model `{model}`: the GPU kernels would contain the constant {value:e}, which is not a finite f32 number; generate with runtime parameters or without GPU kernels"
)]
pub struct KernelError {
    /// The model's name.
    pub model: String,
    /// The constant.
    pub value: f64,
}

/// The GPU kernels of the lowered programs `low` of `model`: one per lowered function in
/// `set` (each frame's of a per-frame function).
pub fn kernels(model: &Model, low: &Lowered, set: FunctionSet) -> Result<Kernels, KernelError> {
    let variants = super::frames::variants(model);
    let sizes = &low.sizes;
    let functions: Vec<_> = low
        .functions
        .iter()
        .filter(|f| set.contains(f.id))
        .collect();
    let entries: Vec<Entry> = functions
        .iter()
        .map(|f| {
            let spec = f.id.spec();
            let name = match f.frame {
                Some(l) => format!("{}_{}", spec.name, variants[l].to_lowercase()),
                None => spec.name.to_owned(),
            };
            let (rows, cols) = spec.shape.size_in(sizes);
            Entry {
                name,
                inputs: spec.inputs,
                rows,
                cols,
            }
        })
        .collect();
    let mimics = low
        .mimic_angles
        .iter()
        .map(|(s, m)| Mimic {
            speed: *s,
            master: m.master as usize,
            multiplier: m.multiplier,
            offset: m.offset,
        })
        .collect();
    let dynamics = Source::dynamics_of(&functions);
    let src = Source {
        low,
        functions,
        entries,
        mimics,
        speeds: model.speeds.len().max(low.dof),
        dynamics,
    };
    let error = |e: print::BadConstant| KernelError {
        model: model.name.clone(),
        value: e.0,
    };
    Ok(Kernels {
        wgsl_f32: kernel::module(&src, Float::F32).map_err(error)?,
        wgsl_f64: kernel::module(&src, Float::F64).map_err(error)?,
        entries: src
            .entries
            .iter()
            .map(|e| (e.name.clone(), e.inputs, e.rows, e.cols))
            .collect(),
        forward_dynamics: src.dynamics.is_some(),
        dof: low.dof,
        params: if low.params.is_runtime() {
            model.params.len()
        } else {
            0
        },
        precomputed: low.pre_slots.len(),
    })
}

/// The `pub mod gpu` of a generated module: the kernels as `&'static str` constants and their
/// layout as a `kanegen_runtime::gpu::GpuModule`.
pub fn rust_module(model: &Model, k: &Kernels) -> String {
    let mut out = String::new();
    out.push_str(
        "\n/// The module's GPU kernels (WGSL compute shaders generated from the same programs as\n\
         /// the functions above) and their layout, for the `kanegen-gpu` crate.\n\
         pub mod gpu {\n",
    );
    for (name, text, what) in [
        ("WGSL_F32", &k.wgsl_f32, "`f32`"),
        (
            "WGSL_F64",
            &k.wgsl_f64,
            "`f64` (adapters with `SHADER_F64`)",
        ),
    ] {
        writeln!(
            out,
            "    /// The kernels in {what}.\n    pub const {name}: &str = r##\"{text}\"##;"
        )
        .expect("string");
    }
    out.push_str(
        "    /// Every per-state entry point: name, inputs, dense result size.\n    \
         pub const KERNELS: &[kanegen_runtime::gpu::Kernel] = &[\n",
    );
    for (name, inputs, rows, cols) in &k.entries {
        let inputs = match inputs {
            Inputs::Q => "Q",
            Inputs::QU => "QU",
            Inputs::QUUd => "QUUd",
        };
        writeln!(
            out,
            "        kanegen_runtime::gpu::Kernel {{ name: \"{name}\", inputs: kanegen_runtime::gpu::KernelInputs::{inputs}, rows: {rows}, cols: {cols} }},"
        )
        .expect("string");
    }
    out.push_str("    ];\n");
    writeln!(
        out,
        "    /// The kernels and their layout.
    pub const MODULE: kanegen_runtime::gpu::GpuModule = kanegen_runtime::gpu::GpuModule {{
        model: \"{}\",
        dof: {},
        params: {},
        precomputed: {},
        workgroup_size: {WORKGROUP_SIZE},
        wgsl_f32: WGSL_F32,
        wgsl_f64: WGSL_F64,
        kernels: KERNELS,
        forward_dynamics: {},
    }};
}}",
        model.name.escape_default(),
        k.dof,
        k.params,
        k.precomputed,
        k.forward_dynamics
    )
    .expect("string");
    out
}
