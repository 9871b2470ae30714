//! The packed forms of a result's series and snapshots, as the store keeps
//! them (`results.series_packed`, `results.snapshots_packed`: BLOB on
//! SQLite, BYTEA on PostgreSQL). Each is a format byte, then a deflate
//! stream of byte-shuffled arrays (`planes`).
//!
//! - `series`: lossless, every column's 64-bit words bit for bit;
//! - `snapshots`: labels, l_k bar and times exact, positions as f32
//!   displacements, per-node fields as scaled f16, contacts as f32 (the
//!   bounds are in its table).
//!
//! What the API serves is the JSON of the decoded values, in the shape the
//! report serialises to; rows stored before the packed columns keep their
//! JSON text and are served as stored.
mod planes;
mod series;
mod snapshots;

pub use series::{pack_series, unpack_series};
pub use snapshots::{pack_snapshots, unpack_snapshots};

/// A packed value that does not decode.
#[derive(Debug, thiserror::Error)]
pub enum CodecError {
    #[error("unknown format {0}")]
    Format(u8),
    #[error("shorter than its arrays")]
    Truncated,
    #[error("{0} bytes after the last array")]
    Trailing(usize),
    #[error("inflating: {0}")]
    Inflate(std::io::Error),
    #[error("a snapshot label is not UTF-8 or no label's word")]
    Label,
}
