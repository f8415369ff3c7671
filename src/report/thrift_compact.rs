//! A minimal writer of the Thrift compact protocol: the encoding of Parquet's page headers
//! and footer ([`super::trace_parquet`]).
//!
//! A struct is a sequence of fields, each a header byte `(id delta << 4) | type` (the delta
//! from the previous field id of the same struct, 1 to 15), then the value, and a stop byte
//! 0. Integers are zigzag varints (`(n << 1) ^ (n >> 63)`, 7 bits a byte, low bits first),
//! binaries a varint length then the bytes, lists a header `(size << 4) | element type`
//! (size below 15; else `0xf0 | type` and a varint size) then the elements. A boolean field
//! carries its value in the header's type (1 true, 2 false).

/// Compact-protocol type ids.
const BOOL_TRUE: u8 = 1;
const BOOL_FALSE: u8 = 2;
const BYTE: u8 = 3;
const I32: u8 = 5;
const I64: u8 = 6;
const BINARY: u8 = 8;
const LIST: u8 = 9;
const STRUCT: u8 = 12;

/// Bytes of compact-protocol structs, written field by field; the field ids of the structs
/// being written are kept on a stack (a nested struct counts its ids from zero).
#[derive(Debug, Default)]
pub(super) struct Compact {
    pub bytes: Vec<u8>,
    last_ids: Vec<i16>,
    last_id: i16,
}

impl Compact {
    pub fn new() -> Compact {
        Compact::default()
    }

    /// An unsigned varint (also the run headers of Parquet's RLE encoding).
    pub fn varint(&mut self, mut n: u64) {
        while n >= 0x80 {
            self.bytes.push((n as u8) | 0x80);
            n >>= 7;
        }
        self.bytes.push(n as u8);
    }

    fn zigzag(&mut self, n: i64) {
        self.varint(((n << 1) ^ (n >> 63)) as u64);
    }

    fn header(&mut self, id: i16, kind: u8) {
        let delta = id - self.last_id;
        if (1..=15).contains(&delta) {
            self.bytes.push(((delta as u8) << 4) | kind);
        } else {
            self.bytes.push(kind);
            self.zigzag(id as i64);
        }
        self.last_id = id;
    }

    pub fn i32(&mut self, id: i16, v: i32) {
        self.header(id, I32);
        self.zigzag(v as i64);
    }

    pub fn i64(&mut self, id: i16, v: i64) {
        self.header(id, I64);
        self.zigzag(v);
    }

    pub fn byte(&mut self, id: i16, v: i8) {
        self.header(id, BYTE);
        self.bytes.push(v as u8);
    }

    pub fn bool(&mut self, id: i16, v: bool) {
        self.header(id, if v { BOOL_TRUE } else { BOOL_FALSE });
    }

    pub fn binary(&mut self, id: i16, v: &[u8]) {
        self.header(id, BINARY);
        self.varint(v.len() as u64);
        self.bytes.extend_from_slice(v);
    }

    /// Opens the struct field `id`; [`Compact::end`] closes it.
    pub fn begin(&mut self, id: i16) {
        self.header(id, STRUCT);
        self.open();
    }

    /// Opens a struct that is a list element (no field header).
    pub fn open(&mut self) {
        self.last_ids.push(self.last_id);
        self.last_id = 0;
    }

    /// Closes the innermost open struct (or ends the top-level one).
    pub fn end(&mut self) {
        self.bytes.push(0);
        self.last_id = self.last_ids.pop().unwrap_or(0);
    }

    /// The header of the list field `id` of `size` elements of compact type `element`.
    fn list(&mut self, id: i16, size: usize, element: u8) {
        self.header(id, LIST);
        if size < 15 {
            self.bytes.push(((size as u8) << 4) | element);
        } else {
            self.bytes.push(0xf0 | element);
            self.varint(size as u64);
        }
    }

    /// A list of i32 (Parquet's enums).
    pub fn i32_list(&mut self, id: i16, values: &[i32]) {
        self.list(id, values.len(), I32);
        for &v in values {
            self.zigzag(v as i64);
        }
    }

    /// A list of binaries (strings).
    pub fn binary_list(&mut self, id: i16, values: &[&[u8]]) {
        self.list(id, values.len(), BINARY);
        for v in values {
            self.varint(v.len() as u64);
            self.bytes.extend_from_slice(v);
        }
    }

    /// The header of a list of `size` structs; each element then [`Compact::open`]s and
    /// [`Compact::end`]s.
    pub fn struct_list(&mut self, id: i16, size: usize) {
        self.list(id, size, STRUCT);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_lists_and_nested_structs_encode_as_the_protocol_says() {
        let mut c = Compact::new();
        c.i32(1, 3); // delta 1, i32: 0x15; zigzag(3) = 6
        c.i64(3, -2); // delta 2, i64: 0x26; zigzag(-2) = 3
        c.begin(20); // delta 17: long form, struct 0x0c, zigzag(20) = 40
        c.bool(1, true); // 0x11
        c.end(); // 0x00
        c.binary(21, b"ab"); // delta 1, binary: 0x18, length 2
        c.i64(22, 300); // 0x16, zigzag(300) = 600 = 0xd8 0x04
        c.i32_list(23, &[1; 15]); // 0x19, long list header 0xf5 then size 15
        c.end();
        let mut want = vec![0x15, 6, 0x26, 3, 0x0c, 40, 0x11, 0x00, 0x18, 2, b'a', b'b'];
        want.extend([0x16, 0xd8, 0x04, 0x19, 0xf5, 15]);
        want.extend([2; 15]);
        want.push(0);
        assert_eq!(c.bytes, want);
    }
}
