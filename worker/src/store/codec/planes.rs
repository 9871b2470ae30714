//! The packed body: typed arrays, each byte-shuffled (the bytes of its
//! words grouped by significance, so that the slowly varying sign and
//! exponent bytes sit together), appended in a fixed order and deflated as
//! one stream behind a format byte. An array written `_along` holds the
//! differences of its values' bit patterns from one to the next (lossless;
//! their high bytes are zero where the values vary smoothly). Nothing in the
//! body says how long an array is: the reader knows from what it read
//! before.
use super::CodecError;
use flate2::Compression;
use flate2::read::DeflateDecoder;
use flate2::write::DeflateEncoder;
use std::io::{Read, Write};

/// Writes arrays in order; [`Packer::finish`] deflates them.
#[derive(Default)]
pub(super) struct Packer {
    body: Vec<u8>,
}

impl Packer {
    pub(super) fn u32s(&mut self, values: impl IntoIterator<Item = u32>) {
        self.shuffled(values.into_iter().map(u32::to_le_bytes));
    }

    pub(super) fn u64s(&mut self, values: impl IntoIterator<Item = u64>) {
        self.shuffled(values.into_iter().map(u64::to_le_bytes));
    }

    pub(super) fn f32s(&mut self, values: impl IntoIterator<Item = f32>) {
        self.shuffled(values.into_iter().map(f32::to_le_bytes));
    }

    pub(super) fn f64s(&mut self, values: impl IntoIterator<Item = f64>) {
        self.shuffled(values.into_iter().map(f64::to_le_bytes));
    }

    pub(super) fn bytes(&mut self, bytes: &[u8]) {
        self.body.extend_from_slice(bytes);
    }

    /// f16 values as the differences of their bit patterns along the array
    /// (lossless; small where the values vary smoothly).
    pub(super) fn f16s_along(&mut self, values: impl IntoIterator<Item = half::f16>) {
        let mut previous = 0u16;
        self.shuffled(values.into_iter().map(|v| {
            let code = v.to_bits();
            let delta = code.wrapping_sub(previous);
            previous = code;
            delta.to_le_bytes()
        }));
    }

    /// f32 values likewise.
    pub(super) fn f32s_along(&mut self, values: impl IntoIterator<Item = f32>) {
        let mut previous = 0u32;
        self.shuffled(values.into_iter().map(|v| {
            let code = v.to_bits();
            let delta = code.wrapping_sub(previous);
            previous = code;
            delta.to_le_bytes()
        }));
    }

    /// Byte `b` of every word, for b = 0 (least significant) upwards.
    fn shuffled<const W: usize>(&mut self, words: impl Iterator<Item = [u8; W]>) {
        let words: Vec<[u8; W]> = words.collect();
        for b in 0..W {
            self.body.extend(words.iter().map(|w| w[b]));
        }
    }

    /// `format`, then the deflated arrays.
    pub(super) fn finish(self, format: u8) -> Vec<u8> {
        let mut deflate = DeflateEncoder::new(vec![format], Compression::best());
        deflate.write_all(&self.body).expect("writing to memory");
        deflate.finish().expect("writing to memory")
    }
}

/// Reads the arrays a [`Packer`] wrote, in the same order.
pub(super) struct Unpacker {
    body: Vec<u8>,
    at: usize,
}

impl Unpacker {
    /// Inflates `packed` after checking its format byte.
    pub(super) fn new(packed: &[u8], format: u8) -> Result<Self, CodecError> {
        match packed.first() {
            Some(&found) if found == format => {}
            Some(&found) => return Err(CodecError::Format(found)),
            None => return Err(CodecError::Truncated),
        }
        let mut body = Vec::new();
        DeflateDecoder::new(&packed[1..])
            .read_to_end(&mut body)
            .map_err(CodecError::Inflate)?;
        Ok(Self { body, at: 0 })
    }

    pub(super) fn u32s(&mut self, n: usize) -> Result<Vec<u32>, CodecError> {
        Ok(self.unshuffled(n)?.into_iter().map(u32::from_le_bytes).collect())
    }

    pub(super) fn u64s(&mut self, n: usize) -> Result<Vec<u64>, CodecError> {
        Ok(self.unshuffled(n)?.into_iter().map(u64::from_le_bytes).collect())
    }

    pub(super) fn f32s(&mut self, n: usize) -> Result<Vec<f32>, CodecError> {
        Ok(self.unshuffled(n)?.into_iter().map(f32::from_le_bytes).collect())
    }

    pub(super) fn f64s(&mut self, n: usize) -> Result<Vec<f64>, CodecError> {
        Ok(self.unshuffled(n)?.into_iter().map(f64::from_le_bytes).collect())
    }

    /// `n` values [`Packer::f16s_along`] wrote.
    pub(super) fn f16s_along(&mut self, n: usize) -> Result<Vec<half::f16>, CodecError> {
        let mut code = 0u16;
        Ok((self.unshuffled(n)?.into_iter())
            .map(|d| {
                code = code.wrapping_add(u16::from_le_bytes(d));
                half::f16::from_bits(code)
            })
            .collect())
    }

    /// `n` values [`Packer::f32s_along`] wrote.
    pub(super) fn f32s_along(&mut self, n: usize) -> Result<Vec<f32>, CodecError> {
        let mut code = 0u32;
        Ok((self.unshuffled(n)?.into_iter())
            .map(|d| {
                code = code.wrapping_add(u32::from_le_bytes(d));
                f32::from_bits(code)
            })
            .collect())
    }

    pub(super) fn bytes(&mut self, n: usize) -> Result<&[u8], CodecError> {
        let end = self.at.checked_add(n).filter(|&end| end <= self.body.len());
        let end = end.ok_or(CodecError::Truncated)?;
        let bytes = &self.body[self.at..end];
        self.at = end;
        Ok(bytes)
    }

    /// `n` words of `W` bytes (checked against what is left before anything
    /// is allocated).
    fn unshuffled<const W: usize>(&mut self, n: usize) -> Result<Vec<[u8; W]>, CodecError> {
        let planes = self.bytes(n.checked_mul(W).ok_or(CodecError::Truncated)?)?;
        Ok((0..n)
            .map(|i| std::array::from_fn(|b| planes[b * n + i]))
            .collect())
    }

    /// Fails unless every byte was read.
    pub(super) fn finish(self) -> Result<(), CodecError> {
        match self.body.len() - self.at {
            0 => Ok(()),
            left => Err(CodecError::Trailing(left)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arrays_come_back_in_order() {
        let mut p = Packer::default();
        p.u32s([1, 2, 3]);
        p.bytes(b"label");
        p.f64s([0.1, -2.5]);
        p.f16s_along([0.5, 0.25, -1.0].map(half::f16::from_f32));
        p.f32s_along([1e-3, 2e-3, -7.5]);
        let packed = p.finish(7);
        let mut u = Unpacker::new(&packed, 7).unwrap();
        assert_eq!(u.u32s(3).unwrap(), [1, 2, 3]);
        assert_eq!(u.bytes(5).unwrap(), b"label");
        assert_eq!(u.f64s(2).unwrap(), [0.1, -2.5]);
        assert_eq!(
            u.f16s_along(3).unwrap(),
            [0.5, 0.25, -1.0].map(half::f16::from_f32)
        );
        assert_eq!(u.f32s_along(3).unwrap(), [1e-3, 2e-3, -7.5]);
        u.finish().unwrap();
    }

    #[test]
    fn a_wrong_format_a_short_body_and_leftovers_are_errors() {
        let mut p = Packer::default();
        p.u32s([1, 2]);
        let packed = p.finish(1);
        assert!(matches!(Unpacker::new(&packed, 2), Err(CodecError::Format(1))));
        assert!(matches!(Unpacker::new(&[], 1), Err(CodecError::Truncated)));
        let mut u = Unpacker::new(&packed, 1).unwrap();
        assert!(matches!(u.u64s(2), Err(CodecError::Truncated)));
        assert!(matches!(u.u32s(usize::MAX), Err(CodecError::Truncated)));
        u.u32s(1).unwrap();
        assert!(matches!(u.finish(), Err(CodecError::Trailing(4))));
    }
}
