//! A series, losslessly: column by column in [`COLUMNS`] order, every value
//! a 64-bit word (a real's IEEE bits, a count as an integer) less the
//! column's previous word (wrapping), so that a slowly varying column leaves
//! its high bytes zero, then byte-shuffled and deflated. Series packed
//! before the knot's own length was measured (format 1) read with it 0.
use super::CodecError;
use super::planes::{Packer, Unpacker};
use solver::measurements::{COLUMNS, Column, Sample};

/// The packed form's format byte, and the format without `l_k_arc_bar`.
const FORMAT: u8 = 2;
const FORMAT_WITHOUT_ARC: u8 = 1;

/// Writes each column's word back into a sample: one per [`COLUMNS`] entry,
/// in its order.
const SETTERS: [fn(&mut Sample, u64); COLUMNS.len()] = [
    |s, w| s.time = f64::from_bits(w),
    |s, w| s.l_k_bar = f64::from_bits(w),
    |s, w| s.l_k_arc_bar = f64::from_bits(w),
    |s, w| s.l_c_over_l = f64::from_bits(w),
    |s, w| s.force = f64::from_bits(w),
    |s, w| s.f_bar = f64::from_bits(w),
    |s, w| s.width = f64::from_bits(w),
    |s, w| s.height = f64::from_bits(w),
    |s, w| s.h_bar = f64::from_bits(w),
    |s, w| s.kinetic_energy = f64::from_bits(w),
    |s, w| s.contacts = w as usize,
    |s, w| s.active_contacts = w as usize,
    |s, w| s.max_penetration_over_h = f64::from_bits(w),
    |s, w| s.epsilon = f64::from_bits(w),
    |s, w| s.phi = f64::from_bits(w),
    |s, w| s.newton_iterations = w as u32,
    |s, w| s.dt = f64::from_bits(w),
    |s, w| s.e_stretch_bar = f64::from_bits(w),
    |s, w| s.e_bend_bar = f64::from_bits(w),
    |s, w| s.e_twist_bar = f64::from_bits(w),
    |s, w| s.e_braid_bar = f64::from_bits(w),
    |s, w| s.e_loop_bar = f64::from_bits(w),
    |s, w| s.lk = f64::from_bits(w),
    |s, w| s.end_turns = f64::from_bits(w),
    |s, w| s.m_bar = f64::from_bits(w),
    |s, w| s.stage = w as usize,
];

/// The word a column stores for a sample.
fn word(column: &Column, s: &Sample) -> u64 {
    match column {
        Column::Real(get) => get(s).to_bits(),
        Column::Count(get) => get(s),
    }
}

/// The series packed: the sample count, then the columns.
pub fn pack_series(series: &[Sample]) -> Vec<u8> {
    pack(series, COLUMNS.iter().map(|(_, column)| column), FORMAT)
}

/// `series` packed by `columns`, behind `format`.
fn pack<'c>(series: &[Sample], columns: impl Iterator<Item = &'c Column>, format: u8) -> Vec<u8> {
    let mut p = Packer::default();
    p.u64s([series.len() as u64]);
    for column in columns {
        let mut previous = 0u64;
        p.u64s(series.iter().map(|s| {
            let w = word(column, s);
            let delta = w.wrapping_sub(previous);
            previous = w;
            delta
        }));
    }
    p.finish(format)
}

/// The series [`pack_series`] packed, bit for bit.
pub fn unpack_series(packed: &[u8]) -> Result<Vec<Sample>, CodecError> {
    let format = match packed.first() {
        Some(&FORMAT_WITHOUT_ARC) => FORMAT_WITHOUT_ARC,
        _ => FORMAT,
    };
    let mut u = Unpacker::new(packed, format)?;
    let n = usize::try_from(u.u64s(1)?[0]).map_err(|_| CodecError::Truncated)?;
    let mut series = vec![Sample::default(); n];
    for (c, set) in SETTERS.iter().enumerate() {
        if format == FORMAT_WITHOUT_ARC && COLUMNS[c].0 == "l_k_arc_bar" {
            continue;
        }
        let mut previous = 0u64;
        let words = u.u64s(n)?;
        for (s, delta) in series.iter_mut().zip(words) {
            previous = previous.wrapping_add(delta);
            set(s, previous);
        }
    }
    u.finish()?;
    Ok(series)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A sample whose every column holds a value of its own (the setters
    /// write the field each column reads).
    fn distinct(k: usize) -> Sample {
        let mut s = Sample::default();
        for (c, set) in SETTERS.iter().enumerate() {
            let value = (100 * k + c + 1) as u64;
            match COLUMNS[c].1 {
                Column::Real(_) => set(&mut s, (value as f64 + 0.25).to_bits()),
                Column::Count(_) => set(&mut s, value),
            }
        }
        s
    }

    #[test]
    fn every_column_has_its_setter() {
        let s = distinct(0);
        for (c, (name, column)) in COLUMNS.iter().enumerate() {
            let expected = match column {
                Column::Real(_) => (c as f64 + 1.25).to_bits(),
                Column::Count(_) => c as u64 + 1,
            };
            assert_eq!(word(column, &s), expected, "column {name}");
        }
        let series: Vec<Sample> = (0..5).map(distinct).collect();
        assert_eq!(unpack_series(&pack_series(&series)).unwrap(), series);
    }

    /// A series packed before `l_k_arc_bar` (format 1: the other columns
    /// in order) reads with it 0.
    #[test]
    fn a_series_packed_without_the_knots_own_length_reads() {
        let series: Vec<Sample> = (0..5).map(distinct).collect();
        let columns = (COLUMNS.iter())
            .filter(|(name, _)| *name != "l_k_arc_bar")
            .map(|(_, column)| column);
        let old = unpack_series(&pack(&series, columns, FORMAT_WITHOUT_ARC)).unwrap();
        let expected: Vec<Sample> = (series.iter())
            .map(|s| Sample {
                l_k_arc_bar: 0.0,
                ..*s
            })
            .collect();
        assert_eq!(old, expected);
    }

    #[test]
    fn an_empty_series_packs() {
        assert_eq!(unpack_series(&pack_series(&[])).unwrap(), []);
    }

    fn sample() -> impl Strategy<Value = Sample> {
        (
            prop::array::uniform16(any::<f64>()),
            prop::array::uniform6(any::<f64>()),
            (any::<u32>(), any::<u32>(), any::<u32>(), any::<u8>()),
        )
            .prop_map(|(a, b, (contacts, active, newton, stage))| {
                let mut s = Sample::default();
                let mut reals = a.into_iter().chain(b);
                for (c, set) in SETTERS.iter().enumerate() {
                    match COLUMNS[c].1 {
                        Column::Real(_) => set(&mut s, reals.next().unwrap().to_bits()),
                        Column::Count(_) => set(&mut s, 0),
                    }
                }
                s.contacts = contacts as usize;
                s.active_contacts = active as usize;
                s.newton_iterations = newton;
                s.stage = stage as usize;
                s
            })
    }

    proptest! {
        /// Lossless: every real comes back with the same bits (NaNs and
        /// signed zeros included), every count the same.
        #[test]
        fn series_round_trip_bit_for_bit(series in prop::collection::vec(sample(), 0..40)) {
            let back = unpack_series(&pack_series(&series)).unwrap();
            prop_assert_eq!(back.len(), series.len());
            for (a, b) in series.iter().zip(&back) {
                for (name, column) in &COLUMNS {
                    prop_assert_eq!(word(column, a), word(column, b), "column {}", name);
                }
            }
        }
    }
}
