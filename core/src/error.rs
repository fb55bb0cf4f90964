//! The one error type of the core.

use core::fmt;

/// Everything that can go wrong in a core stage. Each variant carries enough
/// context for a host to print a useful message without a debugger, and has
/// one meaning. New variants may come in a minor version (the enum is
/// non-exhaustive): match with a fallback arm.
#[derive(Clone, Copy, Debug, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// The caller's arena is too small (in bytes).
    CapacityExceeded {
        /// Bytes the operation needs.
        needed: usize,
        /// Bytes that were provided.
        available: usize,
    },
    /// The caller's output buffer (roots, curves, records) is too small.
    OutputTooSmall {
        /// Elements the operation writes.
        needed: usize,
        /// Elements the buffer holds.
        available: usize,
    },
    /// A parameter is outside its documented domain.
    InvalidArgument(&'static str),
    /// An input value is NaN or infinite.
    NonFinite {
        /// Which input holds the value.
        what: &'static str,
        /// Element index within that input.
        index: usize,
    },
    /// An index refers past the end of the array it indexes.
    OutOfRange {
        /// Which input holds the bad index: an array, or `array.field` for
        /// a field of its records (shown as `array[index].field`).
        what: &'static str,
        /// Element index within that input.
        index: usize,
        /// The offending value.
        value: usize,
        /// The exclusive upper bound it had to respect.
        bound: usize,
    },
    /// An index outside the range `first..=last` its field takes, where
    /// that range does not start at 0 (a trim record's cv: the first point
    /// past the meet, never the root).
    NotBetween {
        /// Which input holds the bad index, as for [`Error::OutOfRange`].
        what: &'static str,
        /// Element index within that input.
        index: usize,
        /// The offending value.
        value: usize,
        /// The smallest value it may take.
        first: usize,
        /// The largest value it may take.
        last: usize,
    },
    /// A strided view does not fit its buffer or has a stride below the element size.
    BadStride {
        /// Which input is malformed.
        what: &'static str,
    },
    /// A finite input value outside the range pelage accepts for it (a
    /// weight outside 0..=1, a coordinate beyond
    /// `surface::mesh::MAX_COORDINATE`: limits that keep every result
    /// finite, documented where the input is).
    OutOfDomain {
        /// Which input holds the value, and its accepted range.
        what: &'static str,
        /// Element index within that input.
        index: usize,
    },
    /// A bound strand's weights (the first `count` of its binding) do not
    /// sum to 1 within
    /// [`WEIGHT_SUM_TOLERANCE`](crate::interp::bind::WEIGHT_SUM_TOLERANCE):
    /// the strand would be longer or shorter than its guides.
    WeightSum {
        /// The strand.
        index: usize,
        /// What its weights sum to (finite: each weight is checked to lie
        /// in 0..=1 first).
        sum: f32,
    },
    /// Serialized bytes are truncated, inconsistent or fail their checksum.
    Corrupt {
        /// What is wrong with them.
        what: &'static str,
    },
    /// Serialized bytes have the wrong magic or a format version this
    /// build does not read.
    VersionMismatch {
        /// The version the bytes carry (0 when the magic is wrong).
        found: u32,
        /// The version this build reads.
        supported: u32,
    },
    /// The caller's progress callback asked to stop.
    Cancelled,
}

// every float an error carries is finite (see `WeightSum`), so equality
// is reflexive
impl Eq for Error {}

impl Error {
    /// The same error with its element index moved by `by`: a check run on
    /// the range starting at `by` reports indices into the whole input.
    pub fn shifted(self, by: usize) -> Error {
        match self {
            Error::NonFinite { what, index } => Error::NonFinite {
                what,
                index: index + by,
            },
            Error::OutOfDomain { what, index } => Error::OutOfDomain {
                what,
                index: index + by,
            },
            Error::NotBetween {
                what,
                index,
                value,
                first,
                last,
            } => Error::NotBetween {
                what,
                index: index + by,
                value,
                first,
                last,
            },
            Error::WeightSum { index, sum } => Error::WeightSum {
                index: index + by,
                sum,
            },
            Error::OutOfRange {
                what,
                index,
                value,
                bound,
            } => Error::OutOfRange {
                what,
                index: index + by,
                value,
                bound,
            },
            other => other,
        }
    }
}

/// Where a value sits: `what[index]`, or `array[index].field` for a
/// `what` of the form `array.field`.
struct Place(&'static str, usize);

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let Place(what, index) = *self;
        match what.split_once('.') {
            Some((array, field)) => write!(f, "{array}[{index}].{field}"),
            None => write!(f, "{what}[{index}]"),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::CapacityExceeded { needed, available } => {
                write!(
                    f,
                    "capacity exceeded: {needed} needed, {available} available"
                )
            }
            Error::OutputTooSmall { needed, available } => {
                write!(
                    f,
                    "output buffer too small: {needed} needed, {available} available"
                )
            }
            Error::InvalidArgument(why) => write!(f, "invalid argument: {why}"),
            Error::NonFinite { what, index } => {
                write!(f, "non-finite value in {what} at element {index}")
            }
            Error::OutOfRange {
                what,
                index,
                value,
                bound,
            } => write!(
                f,
                "{} = {value} is out of range (must be below {bound})",
                Place(what, index)
            ),
            Error::NotBetween {
                what,
                index,
                value,
                first,
                last,
            } => write!(
                f,
                "{} = {value} is out of range (must be from {first} to {last})",
                Place(what, index)
            ),
            Error::BadStride { what } => {
                write!(
                    f,
                    "{what}: stride smaller than the element or buffer too short"
                )
            }
            Error::OutOfDomain { what, index } => {
                write!(
                    f,
                    "value outside the accepted range in {what} at element {index}"
                )
            }
            Error::WeightSum { index, sum } => write!(
                f,
                "bindings[{index}].weights sum to {sum} (must be 1 within {:e})",
                crate::interp::bind::WEIGHT_SUM_TOLERANCE
            ),
            Error::Corrupt { what } => write!(f, "corrupt data: {what}"),
            Error::VersionMismatch { found, supported } => write!(
                f,
                "version mismatch: the data has version {found}, this build reads {supported}"
            ),
            Error::Cancelled => write!(f, "cancelled by the progress callback"),
        }
    }
}
