//! The lane type's layout: every `Lanes<L>` starts on a cache line (so that an 8-lane vector
//! store never straddles two), in arrays and in nalgebra matrices of lanes alike, and
//! `lanes::zeros` is the zero matrix.

use kanegen_runtime::lanes::{Lanes, zeros};
use nalgebra::{SMatrix, SVector};

fn starts_on_a_cache_line<T>(x: &T) -> bool {
    (x as *const T as usize).is_multiple_of(64)
}

#[test]
fn lanes_are_aligned_to_a_cache_line_at_every_width() {
    assert_eq!(align_of::<Lanes<1>>(), 64);
    assert_eq!(align_of::<Lanes<4>>(), 64);
    assert_eq!(align_of::<Lanes<8>>(), 64);
    assert_eq!(align_of::<Lanes<16>>(), 64);
    // 8 lanes fill the line exactly; fewer are padded to it, more take whole lines.
    assert_eq!(size_of::<Lanes<8>>(), 64);
    assert_eq!(size_of::<Lanes<4>>(), 64);
    assert_eq!(size_of::<Lanes<16>>(), 128);
}

#[test]
fn every_entry_of_a_lane_matrix_starts_on_a_cache_line_wherever_it_lives() {
    // On the stack, behind a byte that would misalign an 8-byte-aligned type, and on the heap.
    let (_pad, m) = (1u8, zeros::<19, 19, 8>());
    assert!(m.iter().all(starts_on_a_cache_line));
    let v: Vec<(u8, SVector<Lanes<8>, 19>)> = (0..5).map(|i| (i, zeros())).collect();
    assert!(
        v.iter()
            .flat_map(|(_, v)| v.iter())
            .all(starts_on_a_cache_line)
    );
    let boxed = Box::new(zeros::<19, 19, 4>());
    assert!(boxed.iter().all(starts_on_a_cache_line));
}

#[test]
fn zeros_is_the_zero_matrix_of_lanes() {
    let m: SMatrix<Lanes<8>, 19, 19> = zeros();
    assert_eq!(
        m,
        SMatrix::<Lanes<8>, 19, 19>::from_element(Lanes::splat(0.0))
    );
    // +0.0 in every lane, bit for bit (the by-value batched forms start from it).
    assert!(m.iter().flat_map(|x| x.0).all(|x| x.to_bits() == 0));
    let v: SVector<Lanes<3>, 5> = zeros();
    assert!(v.iter().flat_map(|x| x.0).all(|x| x.to_bits() == 0));
}
