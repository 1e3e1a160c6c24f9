//! A minimal ZIP writer: stored (uncompressed) entries, what an FMU archive needs.
//!
//! The format (PKWARE APPNOTE 4.3): for each file a local header and its bytes, then the
//! central directory (one entry per file, pointing back at its local header) and the end
//! record. Entries are stored (method 0) with their CRC-32; no ZIP64, so the archive and each
//! file stay under 4 GiB (an FMU is a few MB). Timestamps are fixed (1980-01-01), so the same
//! inputs give the same bytes.

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320) of `data`.
pub fn crc32(data: &[u8]) -> u32 {
    static TABLE: std::sync::OnceLock<[u32; 256]> = std::sync::OnceLock::new();
    let table = TABLE.get_or_init(|| {
        let mut t = [0u32; 256];
        for (i, e) in t.iter_mut().enumerate() {
            let mut c = i as u32;
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    0xEDB8_8320 ^ (c >> 1)
                } else {
                    c >> 1
                };
            }
            *e = c;
        }
        t
    });
    let mut c = !0u32;
    for &b in data {
        c = table[((c ^ b as u32) & 0xFF) as usize] ^ (c >> 8);
    }
    !c
}

/// Why an archive could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ZipError {
    /// A file or the archive is too large for a ZIP without ZIP64.
    #[error("{0} is too large for the archive (over 4 GiB or 65535 entries)")]
    TooLarge(String),
}

/// The archive of `files` (path inside the archive with `/` separators, bytes), in order.
pub fn stored(files: &[(&str, &[u8])]) -> Result<Vec<u8>, ZipError> {
    let too_large = |what: &str| ZipError::TooLarge(what.to_string());
    if files.len() > u16::MAX as usize {
        return Err(too_large("the file list"));
    }
    let mut out: Vec<u8> = Vec::new();
    let mut central: Vec<u8> = Vec::new();
    // DOS date 1980-01-01, time 00:00.
    let (dos_time, dos_date) = (0u16, (1u16 << 5) | 1);
    for (name, data) in files {
        let size = u32::try_from(data.len()).map_err(|_| too_large(name))?;
        let name_len = u16::try_from(name.len()).map_err(|_| too_large(name))?;
        let offset = u32::try_from(out.len()).map_err(|_| too_large("the archive"))?;
        let crc = crc32(data);
        let common = |v: &mut Vec<u8>| {
            v.extend_from_slice(&20u16.to_le_bytes()); // version needed: 2.0
            v.extend_from_slice(&0u16.to_le_bytes()); // flags
            v.extend_from_slice(&0u16.to_le_bytes()); // method: stored
            v.extend_from_slice(&dos_time.to_le_bytes());
            v.extend_from_slice(&dos_date.to_le_bytes());
            v.extend_from_slice(&crc.to_le_bytes());
            v.extend_from_slice(&size.to_le_bytes()); // compressed
            v.extend_from_slice(&size.to_le_bytes()); // uncompressed
            v.extend_from_slice(&name_len.to_le_bytes());
            v.extend_from_slice(&0u16.to_le_bytes()); // extra field length
        };
        out.extend_from_slice(&0x0403_4b50u32.to_le_bytes());
        common(&mut out);
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(data);

        central.extend_from_slice(&0x0201_4b50u32.to_le_bytes());
        central.extend_from_slice(&(3u16 << 8 | 20).to_le_bytes()); // made by: Unix, 2.0
        common(&mut central);
        central.extend_from_slice(&0u16.to_le_bytes()); // comment length
        central.extend_from_slice(&0u16.to_le_bytes()); // disk number
        central.extend_from_slice(&0u16.to_le_bytes()); // internal attributes
        // External attributes: a regular file, rw-r--r-- (0o755 for the shared library).
        let mode: u32 = if name.ends_with(".so") {
            0o100755
        } else {
            0o100644
        };
        central.extend_from_slice(&(mode << 16).to_le_bytes());
        central.extend_from_slice(&offset.to_le_bytes());
        central.extend_from_slice(name.as_bytes());
    }
    let cd_offset = u32::try_from(out.len()).map_err(|_| too_large("the archive"))?;
    let cd_size = u32::try_from(central.len()).map_err(|_| too_large("the archive"))?;
    out.extend_from_slice(&central);
    out.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes()); // this disk
    out.extend_from_slice(&0u16.to_le_bytes()); // disk of the central directory
    out.extend_from_slice(&(files.len() as u16).to_le_bytes());
    out.extend_from_slice(&(files.len() as u16).to_le_bytes());
    out.extend_from_slice(&cd_size.to_le_bytes());
    out.extend_from_slice(&cd_offset.to_le_bytes());
    out.extend_from_slice(&0u16.to_le_bytes()); // comment length
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_of_the_standard_check_string() {
        // The CRC catalogue's check value of CRC-32/ISO-HDLC.
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn archive_layout_points_back_at_its_entries() {
        let zip = stored(&[("a.txt", b"hello"), ("dir/b.bin", &[0u8, 1, 2])]).unwrap();
        let u32_at = |i: usize| u32::from_le_bytes(zip[i..i + 4].try_into().unwrap());
        let u16_at = |i: usize| u16::from_le_bytes(zip[i..i + 2].try_into().unwrap());
        let end = zip.len() - 22;
        assert_eq!(u32_at(end), 0x0605_4b50);
        assert_eq!(u16_at(end + 10), 2);
        let cd = u32_at(end + 16) as usize;
        assert_eq!(cd + u32_at(end + 12) as usize, end);
        // The second central entry's local header holds its name and bytes.
        let second = cd + 46 + "a.txt".len();
        assert_eq!(u32_at(second), 0x0201_4b50);
        let local = u32_at(second + 42) as usize;
        assert_eq!(u32_at(local), 0x0403_4b50);
        assert_eq!(&zip[local + 30..local + 39], b"dir/b.bin");
        assert_eq!(&zip[local + 39..local + 42], &[0, 1, 2]);
        assert_eq!(u32_at(local + 14), crc32(&[0, 1, 2]));
    }
}
