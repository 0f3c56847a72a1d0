//! Prusa's binary G-code (`.bgcode`, libbgcode's published specification,
//! version 1): a file header (`GCDE`, version 1, CRC-32 checksums), then
//! blocks in a fixed order — file metadata, printer metadata, thumbnails,
//! print metadata, slicer metadata, G-code — each a header (type,
//! compression, sizes), its parameters, its data and the CRC-32 of all
//! three, little-endian throughout.
//!
//! Metadata blocks are `key=value` lines (the INI encoding), the values of
//! [`crate::output::gcode::metadata::pairs`]: the printer's block holds what
//! the printer checks and shows (model, nozzle, filament, temperatures,
//! time), the print's the filament and time, the slicer's all of it. Each
//! thumbnail is its own block (PNG, JPG or QOI, as the profile asks). The
//! G-code, its thumbnail comments left out (they are blocks here), is cut
//! into blocks of about [`BLOCK`] bytes at line ends, each MeatPack-encoded
//! with its comment lines kept ([`super::meatpack`]) and compressed with
//! heatshrink (window 2¹², look-ahead 2⁴) when that makes it smaller.

use crate::machine::size::{ImageFormat, Thumbnail};

/// G-code bytes per block before encoding (PrusaSlicer's 64 KiB).
pub(crate) const BLOCK: usize = 65_536;

/// Block types.
const FILE_METADATA: u16 = 0;
const GCODE: u16 = 1;
const SLICER_METADATA: u16 = 2;
const PRINTER_METADATA: u16 = 3;
const PRINT_METADATA: u16 = 4;
const THUMBNAIL: u16 = 5;

/// Compressions.
const NONE: u16 = 0;
const HEATSHRINK_12_4: u16 = 3;

/// G-code encodings.
const MEATPACK_COMMENTS: u16 = 2;

/// The metadata of a `.bgcode`, each block's `key=value` pairs.
#[derive(Clone, Debug, Default)]
pub(crate) struct Metadata {
    /// The file's: its producer.
    pub(crate) file: Vec<(String, String)>,
    /// The printer's.
    pub(crate) printer: Vec<(String, String)>,
    /// The print's.
    pub(crate) print: Vec<(String, String)>,
    /// The slicer's (all of it).
    pub(crate) slicer: Vec<(String, String)>,
}

/// The `.bgcode` of ASCII G-code `gcode` with its metadata and thumbnails.
pub(crate) fn encode(
    gcode: &[u8],
    meta: &Metadata,
    thumbnails: &[(Thumbnail, Vec<u8>)],
) -> Vec<u8> {
    let mut out = Vec::with_capacity(gcode.len() / 3);
    out.extend_from_slice(b"GCDE");
    out.extend_from_slice(&1u32.to_le_bytes());
    out.extend_from_slice(&1u16.to_le_bytes()); // CRC-32
    let ini = |pairs: &[(String, String)]| -> Vec<u8> {
        pairs
            .iter()
            .map(|(k, v)| format!("{k}={v}\n"))
            .collect::<String>()
            .into_bytes()
    };
    let encoding = 0u16.to_le_bytes(); // INI
    block(&mut out, FILE_METADATA, &encoding, &ini(&meta.file), None);
    block(
        &mut out,
        PRINTER_METADATA,
        &encoding,
        &ini(&meta.printer),
        None,
    );
    for (t, bytes) in thumbnails {
        let format: u16 = match t.format {
            ImageFormat::Png => 0,
            ImageFormat::Jpg => 1,
            ImageFormat::Qoi => 2,
        };
        let mut params = Vec::with_capacity(6);
        params.extend_from_slice(&format.to_le_bytes());
        params.extend_from_slice(&(t.size.width as u16).to_le_bytes());
        params.extend_from_slice(&(t.size.height as u16).to_le_bytes());
        block(&mut out, THUMBNAIL, &params, bytes, None);
    }
    block(&mut out, PRINT_METADATA, &encoding, &ini(&meta.print), None);
    block(
        &mut out,
        SLICER_METADATA,
        &encoding,
        &ini(&meta.slicer),
        None,
    );
    let text = without_thumbnails(gcode);
    let params = MEATPACK_COMMENTS.to_le_bytes();
    for chunk in lines_in_blocks(&text, BLOCK) {
        let packed = super::meatpack::pack(chunk);
        let shrunk = super::heatshrink::encode(&packed, 12, 4);
        if shrunk.len() < packed.len() {
            block(&mut out, GCODE, &params, &packed, Some(&shrunk));
        } else {
            block(&mut out, GCODE, &params, &packed, None);
        }
    }
    out
}

/// Appends one block: header, `params`, the data (`compressed` with
/// heatshrink 12/4 when given, else `data` itself) and the CRC-32 of all.
fn block(out: &mut Vec<u8>, kind: u16, params: &[u8], data: &[u8], compressed: Option<&[u8]>) {
    let start = out.len();
    out.extend_from_slice(&kind.to_le_bytes());
    let compression = if compressed.is_some() {
        HEATSHRINK_12_4
    } else {
        NONE
    };
    out.extend_from_slice(&compression.to_le_bytes());
    out.extend_from_slice(&(data.len() as u32).to_le_bytes());
    if let Some(c) = compressed {
        out.extend_from_slice(&(c.len() as u32).to_le_bytes());
    }
    out.extend_from_slice(params);
    out.extend_from_slice(compressed.unwrap_or(data));
    let crc = crc32fast::hash(&out[start..]);
    out.extend_from_slice(&crc.to_le_bytes());
}

/// `gcode` without its thumbnail comment blocks (and the `;` line after
/// each).
fn without_thumbnails(gcode: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(gcode.len());
    let mut inside = false;
    let mut after = false;
    for line in gcode.split_inclusive(|&b| b == b'\n') {
        let t = line.strip_suffix(b"\n").unwrap_or(line);
        let begins = [
            &b"; thumbnail begin "[..],
            b"; thumbnail_QOI begin ",
            b"; thumbnail_JPG begin ",
        ]
        .iter()
        .any(|p| t.starts_with(p));
        if begins {
            inside = true;
            continue;
        }
        if inside {
            inside = !matches!(
                t,
                b"; thumbnail end" | b"; thumbnail_QOI end" | b"; thumbnail_JPG end"
            );
            after = !inside;
            continue;
        }
        if after && t == b";" {
            after = false;
            continue;
        }
        after = false;
        out.extend_from_slice(line);
    }
    out
}

/// `text` cut at line ends into pieces of about `size` bytes (a longer
/// line is a piece of its own).
fn lines_in_blocks(text: &[u8], size: usize) -> Vec<&[u8]> {
    let mut out = Vec::new();
    let mut start = 0;
    while start < text.len() {
        let mut end = (start + size).min(text.len());
        if end < text.len() {
            end = match text[start..end].iter().rposition(|&b| b == b'\n') {
                Some(k) => start + k + 1,
                None => text[end..]
                    .iter()
                    .position(|&b| b == b'\n')
                    .map_or(text.len(), |k| end + k + 1),
            };
        }
        out.push(&text[start..end]);
        start = end;
    }
    out
}

/// One block read back: its type, parameters and data (decompressed), from
/// the specification alone.
#[derive(Clone, Debug, PartialEq)]
#[cfg(any(test, feature = "testing"))]
pub struct Block {
    /// Block type.
    pub kind: u16,
    /// Its parameters.
    pub params: Vec<u8>,
    /// Its data, decompressed.
    pub data: Vec<u8>,
}

/// Reads every block of a `.bgcode` back, checking the magic, the version,
/// each CRC-32 and each decompression; None at the first fault.
#[cfg(any(test, feature = "testing"))]
pub fn decode(file: &[u8]) -> Option<Vec<Block>> {
    let u16_at = |i: usize| Some(u16::from_le_bytes(file.get(i..i + 2)?.try_into().ok()?));
    let u32_at = |i: usize| Some(u32::from_le_bytes(file.get(i..i + 4)?.try_into().ok()?));
    if file.get(..4)? != b"GCDE" || u32_at(4)? != 1 || u16_at(8)? != 1 {
        return None;
    }
    let mut i = 10;
    let mut out = Vec::new();
    while i < file.len() {
        let start = i;
        let (kind, compression, size) = (u16_at(i)?, u16_at(i + 2)?, u32_at(i + 4)? as usize);
        i += 8;
        let stored = if compression == NONE {
            size
        } else {
            i += 4;
            u32_at(i - 4)? as usize
        };
        let plen = if kind == THUMBNAIL { 6 } else { 2 };
        let params = file.get(i..i + plen)?.to_vec();
        i += plen;
        let raw = file.get(i..i + stored)?;
        i += stored;
        if crc32fast::hash(&file[start..i]) != u32_at(i)? {
            return None;
        }
        i += 4;
        let data = match compression {
            NONE => raw.to_vec(),
            HEATSHRINK_12_4 => super::heatshrink::decode(raw, size, 12, 4)?,
            _ => return None,
        };
        out.push(Block { kind, params, data });
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_read_back_in_order_with_the_g_code() {
        let mut gcode = String::from("; generated by p3dp\n; thumbnail_QOI begin 2x2 4\n; AAAA\n; thumbnail_QOI end\n;\nG28\n");
        for k in 0..20_000 {
            gcode.push_str(&format!("G1 X{}.{} Y5 E{k}.5 F1200\n", k % 200, k % 10));
        }
        let meta = Metadata {
            file: vec![("Producer".into(), "p3dp".into())],
            printer: vec![("printer_model".into(), "MK4".into())],
            print: vec![("filament used [mm]".into(), "12.5".into())],
            slicer: vec![("nozzle_diameter".into(), "0.4".into())],
        };
        let thumb = Thumbnail {
            size: crate::machine::size::Size {
                width: 2,
                height: 2,
            },
            format: ImageFormat::Qoi,
        };
        let file = encode(gcode.as_bytes(), &meta, &[(thumb, vec![1, 2, 3])]);
        let blocks = decode(&file).unwrap();
        let kinds: Vec<u16> = blocks.iter().map(|b| b.kind).take(5).collect();
        assert_eq!(kinds, [0, 3, 5, 4, 2]);
        assert_eq!(blocks[1].data, b"printer_model=MK4\n");
        assert_eq!(blocks[2].params, [2, 0, 2, 0, 2, 0]);
        let text: Vec<u8> = blocks[5..]
            .iter()
            .flat_map(|b| super::super::meatpack::unpack(&b.data))
            .collect();
        let want: String = gcode
            .lines()
            .skip(5)
            .map(|l| if l.starts_with('G') { l.replace(' ', "") } else { l.to_string() } + "\n")
            .collect();
        assert_eq!(
            String::from_utf8(text).unwrap(),
            format!("; generated by p3dp\n{want}")
        );
        assert!(blocks.len() > 7, "several G-code blocks");
        // a flipped byte fails its block's checksum
        let mut bad = file.clone();
        let k = bad.len() - 10;
        bad[k] ^= 1;
        assert!(decode(&bad).is_none());
    }
}
