//! Fixed-length arrays read from TOML with exactly their number of values.
//!
//! serde's `[T; N]` reads the first N elements of a longer array and drops the rest, so
//! `center_mm = [0, 0, 200, 5]` would pass as a point. Every point, vector and pair key
//! reads through [`array`] (or [`option_array`], [`array_map`]) instead: any other count is
//! a schema error at the value, "expected exactly N values, got M".

use std::collections::BTreeMap;
use std::fmt;
use std::marker::PhantomData;

use serde::de::{Deserialize, Deserializer, Error, SeqAccess, Visitor};

/// `[T; N]` that refuses an array of any other length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exact<T, const N: usize>(pub [T; N]);

impl<'de, T: Deserialize<'de>, const N: usize> Deserialize<'de> for Exact<T, N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Counting<T, const N: usize>(PhantomData<T>);
        impl<'de, T: Deserialize<'de>, const N: usize> Visitor<'de> for Counting<T, N> {
            type Value = Exact<T, N>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                write!(f, "exactly {N} values")
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                let mut values = Vec::with_capacity(N);
                while let Some(v) = seq.next_element()? {
                    if values.len() == N {
                        // Count the rest without keeping it, to say how many were given.
                        let mut given = N + 1;
                        while seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                            given += 1;
                        }
                        return Err(A::Error::invalid_length(given, &self));
                    }
                    values.push(v);
                }
                let given = values.len();
                values
                    .try_into()
                    .map(Exact)
                    .map_err(|_| A::Error::invalid_length(given, &self))
            }
        }
        d.deserialize_seq(Counting::<T, N>(PhantomData))
    }
}

/// `#[serde(deserialize_with = "exact::array")]` for a `[T; N]` field.
pub fn array<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<[T; N], D::Error> {
    Exact::<T, N>::deserialize(d).map(|e| e.0)
}

/// [`array`] for an `Option<[T; N]>` field (with `#[serde(default)]`).
pub fn option_array<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<Option<[T; N]>, D::Error> {
    Option::<Exact<T, N>>::deserialize(d).map(|o| o.map(|e| e.0))
}

/// [`array`] for the values of a `BTreeMap<String, [T; N]>` field.
pub fn array_map<'de, D: Deserializer<'de>, T: Deserialize<'de>, const N: usize>(
    d: D,
) -> Result<BTreeMap<String, [T; N]>, D::Error> {
    BTreeMap::<String, Exact<T, N>>::deserialize(d)
        .map(|m| m.into_iter().map(|(k, v)| (k, v.0)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    struct Point {
        #[serde(deserialize_with = "array")]
        p: [f64; 3],
    }

    fn read(text: &str) -> Result<[f64; 3], String> {
        toml::from_str::<Point>(text)
            .map(|p| p.p)
            .map_err(|e| e.message().to_string())
    }

    #[test]
    fn exactly_three_values_pass_and_any_other_count_is_refused() {
        assert_eq!(read("p = [1, 2.5, -3]"), Ok([1.0, 2.5, -3.0]));
        for (text, given) in [
            ("[1, 2, 3, 4]", 4),
            ("[1, 2, 3, 4, 5]", 5),
            ("[1, 2]", 2),
            ("[]", 0),
        ] {
            let expected = format!("invalid length {given}, expected exactly 3 values");
            assert_eq!(read(&format!("p = {text}")), Err(expected));
        }
    }
}
