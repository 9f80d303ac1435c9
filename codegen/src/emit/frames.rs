//! The body frames of a generated module: the `Frame` type (one variant per link of the model)
//! and, per per-frame registry function, the dispatcher `fn frame_pose(…, frame: Frame)` that
//! calls the straight-line function of the frame (`frame_pose_f10l`).

use proc_macro2::TokenStream;
use quote::quote;

use super::body::state_args;
use super::context::Context;
use super::print::{ident, idx};
use super::signature::arg_names;
use crate::lower::FunctionProgram;
use crate::registry::FunctionId;
use kanegen_model::Model;

/// The `Frame` variant of every link: its name in CamelCase (`base` → `Base`, `link_1` →
/// `Link1`), `F` before a leading digit (`10l` → `F10l`), the link index appended where two
/// would be equal ignoring case.
pub(super) fn variants(model: &Model) -> Vec<String> {
    let mut out: Vec<String> = Vec::with_capacity(model.links.len());
    for (i, link) in model.links.iter().enumerate() {
        let mut v = String::new();
        let mut up = true;
        for ch in link.name.chars() {
            // Letters of every script are kept (`肘` → `肘`, `ψ` → `Ψ`), other characters
            // separate words.
            let letter =
                !ch.is_ascii() && kanegen_model::is_identifier(ch.encode_utf8(&mut [0; 4]));
            if ch.is_ascii_alphanumeric() || letter {
                if up {
                    v.extend(ch.to_uppercase());
                } else {
                    v.push(ch);
                }
                up = false;
            } else {
                up = true;
            }
        }
        if v.is_empty() || v.starts_with(|c: char| c.is_ascii_digit()) {
            v.insert(0, 'F');
        }
        if out.iter().any(|o| o.to_lowercase() == v.to_lowercase()) {
            v.push_str(&i.to_string());
        }
        out.push(v);
    }
    out
}

/// The Rust name of a lowered program: the registry name, with the frame's variant in lower
/// case appended for one frame of a per-frame function (`frame_pose_f10l`).
pub(super) fn rust_name(cx: &Context<'_>, f: &FunctionProgram) -> String {
    let name = f.id.spec().name;
    match f.frame {
        Some(l) => format!("{name}_{}", variants(cx.model)[l].to_lowercase()),
        None => name.to_owned(),
    }
}

/// The `Frame` type: one variant per link, `ALL`, `NAMES`, `name`, `from_name`, `index`.
pub(super) fn frame_type(cx: &Context<'_>) -> TokenStream {
    let model = cx.model;
    let k = idx(model.links.len());
    let variants: Vec<_> = variants(model).iter().map(|v| ident(v)).collect();
    let names: Vec<&str> = model.links.iter().map(|l| l.name.as_str()).collect();
    let docs = names.iter().enumerate().map(|(i, n)| {
        if i == 0 {
            format!(" `{n}` (frame 0, the root).")
        } else {
            format!(" `{n}`.")
        }
    });
    let indices = (0..model.links.len()).map(idx);
    quote! {
        /// The body frames of the model, one per link (the frames of `frame_pose`,
        /// `frame_jacobian`, `frame_bias_acceleration`).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Frame {
            #(#[doc = #docs] #variants = #indices,)*
        }

        impl Frame {
            /// Every frame, in the order of the model's links.
            pub const ALL: [Frame; #k] = [#(Frame::#variants),*];
            /// The frames' names in the model, in the order of [`Frame::ALL`].
            pub const NAMES: [&'static str; #k] = [#(#names),*];

            /// The frame's name in the model (`"10l"`).
            pub fn name(self) -> &'static str {
                Self::NAMES[self as usize]
            }

            /// The frame named `name` in the model, if any.
            pub fn from_name(name: &str) -> Option<Frame> {
                match name {
                    #(#names => Some(Frame::#variants),)*
                    _ => None,
                }
            }

            /// The frame's index in [`Frame::ALL`] (its link's index in the model).
            pub fn index(self) -> usize {
                self as usize
            }
        }
    }
}

/// The public function of per-frame registry function `id`: a `match` on the frame calling the
/// frame's straight-line function.
pub(super) fn dispatcher(cx: &Context<'_>, id: FunctionId) -> TokenStream {
    let spec = id.spec();
    let name = ident(spec.name);
    let doc = format!(" {}", spec.doc);
    let (args, arg_doc) = state_args(cx, spec.inputs);
    let names = arg_names(spec.inputs);
    let (params, forward) = super::body::outer_params(cx);
    let variants = variants(cx.model);
    let arms = cx.low.functions.iter().filter(|f| f.id == id).map(|f| {
        let l = f.frame.expect("a per-frame program has a frame");
        let v = ident(&variants[l]);
        let callee = ident(&rust_name(cx, f));
        quote!(Frame::#v => #callee(#forward #names),)
    });
    let ty = super::signature::result_type(cx, spec.shape);
    quote! {
        #[doc = #doc]
        #[doc = ""]
        #[doc = #arg_doc]
        #[doc = " `frame`: the body frame."]
        #[inline]
        pub fn #name(#params #args, frame: Frame) -> #ty {
            match frame {
                #(#arms)*
            }
        }
    }
}
