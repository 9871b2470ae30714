//! Snapshots, compactly, field by field across the snapshots (each array
//! byte-shuffled, all deflated together; the per-node arrays as differences
//! along the rod, losslessly, `planes`):
//!
//! | field | stored as | comes back within |
//! | --- | --- | --- |
//! | `label` (its word), `l_k_bar`, `time` | UTF-8, f64 | exact |
//! | `points` (m) | f32 of each coordinate's displacement from the previous snapshot as decoded (from 0 for the first snapshot and after a change of node count) | 2^-24 of that displacement (plus f64 rounding): errors do not accumulate |
//! | `twist_rate`, `curvature`, `velocity` | f16 of each value over the snapshot's largest magnitude of the field (an f32) | 2^-11 of the value plus 2^-24 of that largest magnitude |
//! | `contacts`: `a`, `b`, `force`, `normal_force`, `friction_force` | f32 | 2^-24 of the value (f32 rounding) |
//! | `contacts`: `stick` | a byte | exact |
//! | `rods` (node counts per rod) | u32 | exact |
//!
//! Format 1, written before `rods` was stored, reads back with `rods` empty
//! (one rod).
//!
//! The per-node fields are single precision in the report already; f16 keeps
//! what a viewer's colour map shows.
use super::CodecError;
use super::planes::{Packer, Unpacker};
use half::f16;
use solver::snapshot::{Snapshot, SnapshotContact, SnapshotLabel};

/// The packed form's format byte.
const FORMAT: u8 = 2;
/// The format written before `rods` was stored: read, never written.
const FORMAT_WITHOUT_RODS: u8 = 1;

/// The snapshots packed.
pub fn pack_snapshots(snapshots: &[Snapshot]) -> Vec<u8> {
    let mut p = Packer::default();
    p.u32s([snapshots.len() as u32]);
    let labels: Vec<String> = snapshots.iter().map(|s| s.label.to_string()).collect();
    p.u32s(labels.iter().map(|l| l.len() as u32));
    let lengths: [fn(&Snapshot) -> usize; 6] = [
        |s| s.points.len(),
        |s| s.twist_rate.len(),
        |s| s.curvature.len(),
        |s| s.velocity.len(),
        |s| s.contacts.len(),
        |s| s.rods.len(),
    ];
    for length in lengths {
        p.u32s(snapshots.iter().map(|s| length(s) as u32));
    }
    p.u32s(snapshots.iter().flat_map(|s| &s.rods).map(|&nodes| nodes as u32));
    for label in &labels {
        p.bytes(label.as_bytes());
    }
    p.f64s(snapshots.iter().map(|s| s.l_k_bar));
    p.f64s(snapshots.iter().map(|s| s.time));
    let mut previous: Vec<[f64; 3]> = Vec::new();
    for s in snapshots {
        let reference = reference(&previous, s.points.len());
        let displacements: Vec<[f32; 3]> = (s.points.iter().zip(&reference))
            .map(|(x, r)| std::array::from_fn(|k| (x[k] - r[k]) as f32))
            .collect();
        for k in 0..3 {
            p.f32s_along(displacements.iter().map(|d| d[k]));
        }
        previous = displaced(&reference, &displacements);
    }
    for s in snapshots {
        scaled(&mut p, &s.twist_rate);
        scaled(&mut p, &s.curvature);
        let velocity: Vec<f32> = (0..3)
            .flat_map(|k| s.velocity.iter().map(move |v| v[k]))
            .collect();
        scaled(&mut p, &velocity);
    }
    let contacts: Vec<&SnapshotContact> = snapshots.iter().flat_map(|s| &s.contacts).collect();
    for k in 0..3 {
        p.f32s(contacts.iter().map(|c| c.a[k] as f32));
        p.f32s(contacts.iter().map(|c| c.b[k] as f32));
        p.f32s(contacts.iter().map(|c| c.normal_force[k] as f32));
        p.f32s(contacts.iter().map(|c| c.friction_force[k] as f32));
    }
    p.f32s(contacts.iter().map(|c| c.force as f32));
    p.bytes(&contacts.iter().map(|c| u8::from(c.stick)).collect::<Vec<u8>>());
    p.finish(FORMAT)
}

/// The snapshots [`pack_snapshots`] packed, within the bounds of the
/// module's table (format 1's with `rods` empty).
pub fn unpack_snapshots(packed: &[u8]) -> Result<Vec<Snapshot>, CodecError> {
    let format = match packed.first() {
        Some(&FORMAT_WITHOUT_RODS) => FORMAT_WITHOUT_RODS,
        _ => FORMAT,
    };
    let mut u = Unpacker::new(packed, format)?;
    let n = u.u32s(1)?[0] as usize;
    let arrays = if format == FORMAT { 7 } else { 6 };
    let mut lengths = Vec::new();
    for _ in 0..arrays {
        lengths.push(u.u32s(n)?.into_iter().map(|l| l as usize).collect::<Vec<usize>>());
    }
    lengths.resize(7, vec![0; n]);
    let [
        label_len,
        point_len,
        twist_len,
        curvature_len,
        velocity_len,
        contact_len,
        rod_len,
    ] = <[Vec<usize>; 7]>::try_from(lengths).expect("seven arrays");
    let total_rods = rod_len.iter().try_fold(0usize, |sum, &l| sum.checked_add(l));
    let mut rods = u
        .u32s(total_rods.ok_or(CodecError::Truncated)?)?
        .into_iter()
        .map(|r| r as usize);
    let mut labels = Vec::with_capacity(n);
    for &len in &label_len {
        let word = std::str::from_utf8(u.bytes(len)?).map_err(|_| CodecError::Label)?;
        labels.push(SnapshotLabel::parse(word).map_err(|_| CodecError::Label)?);
    }
    let l_k_bar = u.f64s(n)?;
    let time = u.f64s(n)?;
    let mut points: Vec<Vec<[f64; 3]>> = Vec::with_capacity(n);
    let mut previous: &[[f64; 3]] = &[];
    for &len in &point_len {
        let reference = reference(previous, len);
        let [x, y, z] = [u.f32s_along(len)?, u.f32s_along(len)?, u.f32s_along(len)?];
        let displacements: Vec<[f32; 3]> = (0..len).map(|i| [x[i], y[i], z[i]]).collect();
        points.push(displaced(&reference, &displacements));
        previous = points.last().expect("just pushed");
    }
    let mut scalars = Vec::with_capacity(n);
    for i in 0..n {
        let twist_rate = unscaled(&mut u, twist_len[i])?;
        let curvature = unscaled(&mut u, curvature_len[i])?;
        let v = unscaled(&mut u, 3 * velocity_len[i])?;
        let m = velocity_len[i];
        let velocity: Vec<[f32; 3]> = (0..m).map(|j| [v[j], v[m + j], v[2 * m + j]]).collect();
        scalars.push((twist_rate, curvature, velocity));
    }
    let c: usize = contact_len.iter().sum();
    let mut vectors = Vec::with_capacity(12);
    for _ in 0..12 {
        vectors.push(u.f32s(c)?);
    }
    let vector = |first: usize, j: usize| std::array::from_fn(|k| f64::from(vectors[4 * k + first][j]));
    let force = u.f32s(c)?;
    let stick = u.bytes(c)?.to_vec();
    let mut contacts = (0..c).map(|j| SnapshotContact {
        a: vector(0, j),
        b: vector(1, j),
        force: f64::from(force[j]),
        normal_force: vector(2, j),
        friction_force: vector(3, j),
        stick: stick[j] != 0,
    });
    let snapshots = (labels.into_iter().zip(points).zip(scalars).enumerate())
        .map(
            |(i, ((label, points), (twist_rate, curvature, velocity)))| Snapshot {
                label,
                l_k_bar: l_k_bar[i],
                time: time[i],
                points,
                twist_rate,
                curvature,
                velocity,
                contacts: contacts.by_ref().take(contact_len[i]).collect(),
                rods: rods.by_ref().take(rod_len[i]).collect(),
            },
        )
        .collect();
    u.finish()?;
    Ok(snapshots)
}

/// What a snapshot of `len` nodes is displaced from: the previous one as
/// decoded when it has as many nodes, the origin otherwise.
fn reference(previous: &[[f64; 3]], len: usize) -> Vec<[f64; 3]> {
    if previous.len() == len {
        previous.to_vec()
    } else {
        vec![[0.0; 3]; len]
    }
}

/// The decoded positions: `reference` plus `displacements`.
fn displaced(reference: &[[f64; 3]], displacements: &[[f32; 3]]) -> Vec<[f64; 3]> {
    (reference.iter().zip(displacements))
        .map(|(r, d)| std::array::from_fn(|k| r[k] + f64::from(d[k])))
        .collect()
}

/// The largest finite magnitude of `values`, 1 when there is none or it is 0.
fn scale_of(values: &[f32]) -> f32 {
    let largest = (values.iter().copied())
        .filter(|v| v.is_finite())
        .fold(0.0f32, |m, v| m.max(v.abs()));
    if largest > 0.0 { largest } else { 1.0 }
}

/// The scale, then each value over it as f16.
fn scaled(p: &mut Packer, values: &[f32]) {
    let scale = scale_of(values);
    p.f32s([scale]);
    p.f16s_along(values.iter().map(|v| f16::from_f32(v / scale)));
}

/// `n` values [`scaled`] wrote.
fn unscaled(u: &mut Unpacker, n: usize) -> Result<Vec<f32>, CodecError> {
    let scale = u.f32s(1)?[0];
    Ok(u.f16s_along(n)?.into_iter().map(|v| v.to_f32() * scale).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A value of any sign whose magnitude spans 12 decades.
    fn magnitude() -> impl Strategy<Value = f32> {
        (-1.0f32..1.0, -8i32..4).prop_map(|(m, e)| m * 10f32.powi(e))
    }

    fn contact() -> impl Strategy<Value = SnapshotContact> {
        (
            prop::array::uniform3(-1.0f64..1.0),
            prop::array::uniform3(-1.0f64..1.0),
            0.0f64..10.0,
            prop::array::uniform3(-10.0f64..10.0),
            prop::array::uniform3(-10.0f64..10.0),
            any::<bool>(),
        )
            .prop_map(
                |(a, b, force, normal_force, friction_force, stick)| SnapshotContact {
                    a,
                    b,
                    force,
                    normal_force,
                    friction_force,
                    stick,
                },
            )
    }

    /// Snapshots of `nodes` nodes moving a little between them (as a
    /// report's do), one rod or two (a bend's, split at `cut`), some with
    /// per-node fields left empty (as snapshots stored before those fields
    /// were recorded).
    fn snapshots() -> impl Strategy<Value = Vec<Snapshot>> {
        (1usize..30).prop_flat_map(|nodes| {
            prop::collection::vec(
                (
                    prop::sample::select(SnapshotLabel::all()),
                    -500.0f64..500.0,
                    0.0f64..100.0,
                    prop::collection::vec(prop::array::uniform3(-0.5f64..0.5), nodes),
                    prop::collection::vec(prop::array::uniform3(-1e-3f64..1e-3), nodes),
                    any::<bool>(),
                    prop::collection::vec(magnitude(), nodes),
                    prop::collection::vec(magnitude(), nodes),
                    prop::collection::vec(prop::array::uniform3(magnitude()), nodes),
                    prop::collection::vec(contact(), 0..6),
                    0..nodes,
                ),
                0..8,
            )
            .prop_map(move |shots| {
                let mut drift = 0.0;
                (shots.into_iter())
                    .map(
                        |(
                            label,
                            l_k_bar,
                            time,
                            base,
                            moved,
                            full,
                            twist,
                            curvature,
                            velocity,
                            contacts,
                            cut,
                        )| {
                            drift += 1e-3;
                            let points = base
                                .iter()
                                .zip(&moved)
                                .map(|(b, m)| std::array::from_fn(|k| 0.1 * b[k] + m[k] + drift))
                                .collect();
                            Snapshot {
                                label,
                                l_k_bar,
                                time,
                                points,
                                twist_rate: if full { twist } else { Vec::new() },
                                curvature: if full { curvature } else { Vec::new() },
                                velocity: if full { velocity } else { Vec::new() },
                                contacts,
                                rods: if cut == 0 {
                                    Vec::new()
                                } else {
                                    vec![cut, nodes - cut]
                                },
                            }
                        },
                    )
                    .collect()
            })
        })
    }

    /// `back` is within 2^-11 of `value` plus 2^-24 of `scale`.
    fn within_f16(value: f32, back: f32, scale: f32) -> bool {
        (back - value).abs() <= 2f32.powi(-11) * value.abs() * 1.001 + 2f32.powi(-24) * scale
    }

    fn within_f32(value: f64, back: f64) -> bool {
        (back - value).abs() <= 2f64.powi(-24) * value.abs()
    }

    proptest! {
        /// The bounds of the module's table.
        #[test]
        fn snapshots_round_trip_within_the_documented_bounds(shots in snapshots()) {
            let back = unpack_snapshots(&pack_snapshots(&shots)).unwrap();
            prop_assert_eq!(back.len(), shots.len());
            let mut previous: Vec<[f64; 3]> = Vec::new();
            for (s, b) in shots.iter().zip(&back) {
                prop_assert_eq!(&s.label, &b.label);
                prop_assert_eq!(s.l_k_bar.to_bits(), b.l_k_bar.to_bits());
                prop_assert_eq!(s.time.to_bits(), b.time.to_bits());
                prop_assert_eq!(&s.rods, &b.rods);
                prop_assert_eq!(s.points.len(), b.points.len());
                let reference = reference(&previous, s.points.len());
                for ((x, y), r) in s.points.iter().zip(&b.points).zip(&reference) {
                    for k in 0..3 {
                        let bound = 2f64.powi(-24) * (x[k] - r[k]).abs() + 2.0 * f64::EPSILON * x[k].abs();
                        prop_assert!((y[k] - x[k]).abs() <= bound, "{} vs {} (from {})", x[k], y[k], r[k]);
                    }
                }
                previous = b.points.clone();
                for (values, backs) in [(&s.twist_rate, &b.twist_rate), (&s.curvature, &b.curvature)] {
                    prop_assert_eq!(values.len(), backs.len());
                    let scale = scale_of(values);
                    for (v, w) in values.iter().zip(backs.iter()) {
                        prop_assert!(within_f16(*v, *w, scale), "{} vs {} (scale {})", v, w, scale);
                    }
                }
                prop_assert_eq!(s.velocity.len(), b.velocity.len());
                let scale = scale_of(s.velocity.as_flattened());
                for (v, w) in s.velocity.as_flattened().iter().zip(b.velocity.as_flattened()) {
                    prop_assert!(within_f16(*v, *w, scale), "{} vs {} (scale {})", v, w, scale);
                }
                prop_assert_eq!(s.contacts.len(), b.contacts.len());
                for (c, d) in s.contacts.iter().zip(&b.contacts) {
                    prop_assert_eq!(c.stick, d.stick);
                    prop_assert!(within_f32(c.force, d.force));
                    for k in 0..3 {
                        prop_assert!(within_f32(c.a[k], d.a[k]));
                        prop_assert!(within_f32(c.b[k], d.b[k]));
                        prop_assert!(within_f32(c.normal_force[k], d.normal_force[k]));
                        prop_assert!(within_f32(c.friction_force[k], d.friction_force[k]));
                    }
                }
            }
        }
    }

    /// A value packed in format 1 (before `rods` was stored): one snapshot
    /// of two nodes, no per-node fields and no contacts, array by array in
    /// that format's order, reads back as one rod.
    #[test]
    fn format_1_reads_back_as_one_rod() {
        let mut p = Packer::default();
        p.u32s([1]);
        for len in [7, 2, 0, 0, 0, 0] {
            p.u32s([len]);
        }
        p.bytes(b"relaxed");
        p.f64s([150.0]);
        p.f64s([0.5]);
        for k in 0..3 {
            p.f32s_along([0.0, 0.25 * (k + 1) as f32]);
        }
        for _ in 0..3 {
            p.f32s([1.0]);
            p.f16s_along([]);
        }
        for _ in 0..13 {
            p.f32s([]);
        }
        p.bytes(&[]);
        let back = unpack_snapshots(&p.finish(FORMAT_WITHOUT_RODS)).unwrap();
        assert_eq!(
            back,
            [Snapshot {
                label: SnapshotLabel::Relaxed,
                l_k_bar: 150.0,
                time: 0.5,
                points: vec![[0.0; 3], [0.25, 0.5, 0.75]],
                twist_rate: Vec::new(),
                curvature: Vec::new(),
                velocity: Vec::new(),
                contacts: Vec::new(),
                rods: Vec::new(),
            }]
        );
    }

    #[test]
    fn a_label_that_is_not_utf8_or_no_labels_word_is_an_error() {
        let shot = Snapshot {
            label: SnapshotLabel::parse("at_inversion").unwrap(),
            l_k_bar: 0.0,
            time: 0.0,
            points: Vec::new(),
            twist_rate: Vec::new(),
            curvature: Vec::new(),
            velocity: Vec::new(),
            contacts: Vec::new(),
            rods: Vec::new(),
        };
        let good = pack_snapshots(std::slice::from_ref(&shot));
        assert_eq!(unpack_snapshots(&good).unwrap(), [shot]);
        let mut p = Packer::default();
        p.u32s([1]);
        for len in [2, 0, 0, 0, 0, 0, 0] {
            p.u32s([len]);
        }
        p.bytes(&[0xc3, 0x28]);
        assert!(matches!(
            unpack_snapshots(&p.finish(FORMAT)),
            Err(CodecError::Label)
        ));
        // A word that is no label's (the label's bytes are read first).
        let mut p = Packer::default();
        p.u32s([1]);
        for len in [4, 0, 0, 0, 0, 0, 0] {
            p.u32s([len]);
        }
        p.bytes(b"snap");
        let renamed = p.finish(FORMAT);
        assert!(matches!(unpack_snapshots(&renamed), Err(CodecError::Label)));
    }
}
