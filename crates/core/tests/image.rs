//! The model image: the writer reproduces the layout `tcomp image` wrote before the format moved into
//! the core, refuses what it must, and the reader accepts what the writer writes.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use proptest::prelude::*;
use tcomp_core::blob::crc32;
use tcomp_core::image::{
    ENTRY_LEN, HEADER_LEN, Image, ImageError, MAGIC, MAX_ENTRIES, image_len, write_image,
};

/// The layout code of `tcomp image` before it used the core's writer, kept verbatim (apart from
/// taking the blobs as an argument) as the reference the writer must match byte for byte.
fn old_host_layout(blobs: &[(u16, Vec<u8>)]) -> Vec<u8> {
    let table_end = HEADER_LEN + ENTRY_LEN * blobs.len();
    let mut table = Vec::new();
    let mut body = Vec::new();
    let mut offset = table_end.next_multiple_of(4);
    for (id, bytes) in blobs {
        table.extend_from_slice(&id.to_le_bytes());
        table.extend_from_slice(&0u16.to_le_bytes());
        table.extend_from_slice(&(offset as u32).to_le_bytes());
        table.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
        body.extend_from_slice(bytes);
        body.resize(body.len().next_multiple_of(4), 0);
        offset = table_end.next_multiple_of(4) + body.len();
    }
    let mut image = Vec::with_capacity(offset);
    image.extend_from_slice(&MAGIC);
    image.extend_from_slice(&1u16.to_le_bytes());
    image.extend_from_slice(&(blobs.len() as u16).to_le_bytes());
    image.extend_from_slice(&crc32(&table).to_le_bytes());
    image.extend_from_slice(&table);
    image.resize(table_end.next_multiple_of(4), 0);
    image.extend_from_slice(&body);
    image
}

fn entries_of(blobs: &[(u16, Vec<u8>)]) -> Vec<(u16, &[u8])> {
    blobs.iter().map(|(id, b)| (*id, b.as_slice())).collect()
}

/// Writes into a buffer of garbage exactly as long as needed plus `spare` bytes.
fn write(blobs: &[(u16, Vec<u8>)], spare: usize) -> Result<Vec<u8>, ImageError> {
    let entries = entries_of(blobs);
    let len = image_len(&entries)?;
    let mut buf = vec![0xA5; len + spare];
    let written = write_image(&entries, &mut buf)?;
    assert_eq!(written, len);
    assert!(
        buf[len..].iter().all(|&b| b == 0xA5),
        "bytes past the image untouched"
    );
    buf.truncate(len);
    Ok(buf)
}

fn blob(len: usize, seed: u8) -> Vec<u8> {
    (0..len)
        .map(|i| (i as u8).wrapping_mul(31) ^ seed)
        .collect()
}

/// The first bytes (header and table) of two images the old `tcomp image` wrote from the firmware's
/// 1287-byte smoke blob: `--model 6=… --model 0=… --model 3=…` and `--model 2=…`. The header and
/// table depend only on the ids and the blob lengths.
const OLD_HEAD_6_0_3: [u8; 48] = [
    0x54, 0x43, 0x4d, 0x49, 0x01, 0x00, 0x03, 0x00, 0x9c, 0x26, 0x23, 0x79, 0x06, 0x00, 0x00, 0x00,
    0x30, 0x00, 0x00, 0x00, 0x07, 0x05, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x38, 0x05, 0x00, 0x00,
    0x07, 0x05, 0x00, 0x00, 0x03, 0x00, 0x00, 0x00, 0x40, 0x0a, 0x00, 0x00, 0x07, 0x05, 0x00, 0x00,
];
const OLD_HEAD_2: [u8; 24] = [
    0x54, 0x43, 0x4d, 0x49, 0x01, 0x00, 0x01, 0x00, 0x3c, 0x88, 0xac, 0xa3, 0x02, 0x00, 0x00, 0x00,
    0x18, 0x00, 0x00, 0x00, 0x07, 0x05, 0x00, 0x00,
];

#[test]
fn writer_matches_the_images_the_old_tool_wrote() {
    let blobs: Vec<_> = [6u16, 0, 3]
        .iter()
        .map(|&id| (id, blob(1287, id as u8)))
        .collect();
    let image = write(&blobs, 7).unwrap();
    assert_eq!(image.len(), 3912, "the old tool's file size");
    assert_eq!(image[..48], OLD_HEAD_6_0_3);
    assert_eq!(image, old_host_layout(&blobs));
    let image = write(&[(2, blob(1287, 9))], 0).unwrap();
    assert_eq!(image.len(), 1312);
    assert_eq!(image[..24], OLD_HEAD_2);
}

#[test]
fn writer_matches_the_old_layout_for_every_padding() {
    // Every blob length modulo 4, empty blobs, no blobs, and a full table.
    let mut sets: Vec<Vec<(u16, Vec<u8>)>> = vec![vec![]];
    for len in 0..9 {
        sets.push(vec![(7, blob(len, 1))]);
        sets.push(vec![
            (1, blob(len, 2)),
            (0, blob(3, 3)),
            (65535, blob(len + 1, 4)),
        ]);
    }
    sets.push(
        (0..MAX_ENTRIES as u16)
            .map(|id| (id * 3, blob(id as usize, id as u8)))
            .collect(),
    );
    for blobs in &sets {
        let image = write(blobs, 5).unwrap();
        assert_eq!(image, old_host_layout(blobs), "{} blobs", blobs.len());
        assert_eq!(image.len() % 4, 0);
    }
}

#[test]
fn writer_refuses_duplicates_too_many_and_short_buffers() {
    let dup = [(4u16, &[1u8, 2][..]), (5, &[3][..]), (4, &[][..])];
    let mut buf = [0u8; 256];
    assert_eq!(write_image(&dup, &mut buf), Err(ImageError::DuplicateId(4)));
    assert_eq!(image_len(&dup), Err(ImageError::DuplicateId(4)));

    let many: Vec<(u16, &[u8])> = (0..=MAX_ENTRIES as u16).map(|id| (id, &[][..])).collect();
    let mut buf = vec![0u8; 4096];
    assert_eq!(
        write_image(&many, &mut buf),
        Err(ImageError::TooManyEntries)
    );
    assert!(write_image(&many[..MAX_ENTRIES], &mut buf).is_ok());

    let two = [(1u16, &[9u8; 5][..]), (2, &[8u8; 4][..])];
    let needed = image_len(&two).unwrap();
    assert_eq!(needed, 12 + 24 + 8 + 4);
    for short in 0..needed {
        let mut buf = vec![0u8; short];
        assert_eq!(
            write_image(&two, &mut buf),
            Err(ImageError::BufferTooSmall { needed }),
            "{short}-byte buffer"
        );
    }
    let mut buf = vec![0u8; needed];
    assert_eq!(write_image(&two, &mut buf), Ok(needed));
}

#[test]
fn reader_reports_each_fault() {
    let blobs = vec![(3u16, blob(10, 1)), (9, blob(5, 2))];
    let image = write(&blobs, 0).unwrap();
    let parsed = Image::parse(&image).unwrap();
    assert_eq!(parsed.len(), 2);
    assert_eq!(parsed.blob(9).unwrap(), &blobs[1].1[..]);
    assert_eq!(parsed.blob(4), Err(ImageError::Missing));
    assert_eq!(parsed.entry(2), Err(ImageError::Missing));

    assert_eq!(Image::parse(&[0xFF; 64]).unwrap_err(), ImageError::NoImage);
    assert_eq!(Image::parse(&[0; 64]).unwrap_err(), ImageError::NoImage);
    assert_eq!(Image::parse(&image[..3]).unwrap_err(), ImageError::NoImage);

    // Version 2 is read too (its own tests are in `image_v2.rs`); version 3 is not.
    let mut v3 = image.clone();
    v3[4] = 3;
    assert_eq!(
        Image::parse(&v3).unwrap_err(),
        ImageError::UnsupportedVersion(3)
    );

    let mut flipped = image.clone();
    flipped[HEADER_LEN + 1] ^= 0x40;
    assert_eq!(Image::parse(&flipped).unwrap_err(), ImageError::Checksum);

    assert_eq!(
        Image::parse(&image[..HEADER_LEN + 20]).unwrap_err(),
        ImageError::BadTable
    );
    let mut many = image.clone();
    many[6] = MAX_ENTRIES as u8 + 1;
    assert_eq!(Image::parse(&many).unwrap_err(), ImageError::BadTable);

    // The table is intact but the region was cut short: the last blob is out of bounds, the first
    // still loads.
    let cut = &image[..image.len() - 4];
    let parsed = Image::parse(cut).unwrap();
    assert_eq!(parsed.blob(9), Err(ImageError::OutOfBounds));
    assert_eq!(parsed.blob(3).unwrap(), &blobs[0].1[..]);
}

#[test]
fn errors_display_a_reason() {
    for e in [
        ImageError::NoImage,
        ImageError::UnsupportedVersion(7),
        ImageError::DuplicateId(3),
        ImageError::BufferTooSmall { needed: 40 },
        ImageError::TooManyEntries,
        ImageError::TooLarge,
    ] {
        assert!(!e.to_string().is_empty());
    }
    assert!(ImageError::DuplicateId(3).to_string().contains('3'));
    assert!(
        ImageError::BufferTooSmall { needed: 40 }
            .to_string()
            .contains("40")
    );
}

// ---- Fuzzing --------------------------------------------------------------------------------

/// Cases per fuzz property in the normal `cargo test` run.
const FUZZ_CASES: u32 = 100_000;

/// What a fuzz case does to a valid image before the reader sees it.
#[derive(Clone, Debug)]
enum Mutation {
    None,
    Count(u16),
    Version(u16),
    Id { entry: usize, id: u16 },
    Offset { entry: usize, value: u32 },
    Length { entry: usize, value: u32 },
    Truncate(usize),
    Append(Vec<u8>),
    Byte { at: usize, value: u8 },
}

/// A value near an interesting boundary of an image `len` bytes long, or anything.
fn boundary_u32() -> impl Strategy<Value = u32> {
    prop_oneof![
        0u32..80,
        Just(u32::MAX),
        (u32::MAX - 8)..=u32::MAX,
        any::<u32>(),
        Just(0x8000_0000),
    ]
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let entry = 0usize..8;
    prop_oneof![
        1 => Just(Mutation::None),
        2 => prop_oneof![0u16..40, any::<u16>()].prop_map(Mutation::Count),
        1 => prop_oneof![Just(0u16), Just(2), Just(3), any::<u16>()].prop_map(Mutation::Version),
        2 => (entry.clone(), 0u16..8).prop_map(|(entry, id)| Mutation::Id { entry, id }),
        3 => (entry.clone(), boundary_u32()).prop_map(|(entry, value)| Mutation::Offset { entry, value }),
        3 => (entry, boundary_u32()).prop_map(|(entry, value)| Mutation::Length { entry, value }),
        2 => (0usize..200).prop_map(Mutation::Truncate),
        1 => proptest::collection::vec(any::<u8>(), 0..40).prop_map(Mutation::Append),
        2 => (0usize..200, any::<u8>()).prop_map(|(at, value)| Mutation::Byte { at, value }),
    ]
}

/// Applies `m` to `image`, then recomputes the table CRC for the count the header now claims (when
/// that table lies inside the bytes), so the mutation reaches the code behind the checksum.
fn mutate(image: &mut Vec<u8>, m: &Mutation, fix_crc: bool) {
    let put = |image: &mut Vec<u8>, at: usize, bytes: &[u8]| {
        if let Some(dst) = image.get_mut(at..at + bytes.len()) {
            dst.copy_from_slice(bytes);
        }
    };
    let entry_at = |entry: usize| HEADER_LEN + ENTRY_LEN * entry;
    match m {
        Mutation::None => {}
        Mutation::Count(c) => put(image, 6, &c.to_le_bytes()),
        Mutation::Version(v) => put(image, 4, &v.to_le_bytes()),
        Mutation::Id { entry, id } => put(image, entry_at(*entry), &id.to_le_bytes()),
        Mutation::Offset { entry, value } => put(image, entry_at(*entry) + 4, &value.to_le_bytes()),
        Mutation::Length { entry, value } => put(image, entry_at(*entry) + 8, &value.to_le_bytes()),
        Mutation::Truncate(len) => image.truncate(*len),
        Mutation::Append(bytes) => image.extend_from_slice(bytes),
        Mutation::Byte { at, value } => put(image, *at, &[*value]),
    }
    if fix_crc && image.len() >= HEADER_LEN {
        let count = usize::from(u16::from_le_bytes([image[6], image[7]]));
        if let Some(table) = image.get(HEADER_LEN..HEADER_LEN + ENTRY_LEN * count) {
            let crc = crc32(table);
            image[8..12].copy_from_slice(&crc.to_le_bytes());
        }
    }
}

/// The properties every input must satisfy: no panic (the harness catches one), entries inside the
/// bytes, lookups consistent with the table, and an accepted image with readable entries and
/// distinct ids rewritten by the writer reads back the same.
fn check_reader(bytes: &[u8]) -> Result<(), TestCaseError> {
    let Ok(image) = Image::parse(bytes) else {
        return Ok(());
    };
    prop_assert!(image.len() <= MAX_ENTRIES);
    prop_assert_eq!(image.is_empty(), image.entries().next().is_none());
    let region = bytes.as_ptr_range();
    let mut entries = Vec::new();
    for (i, entry) in image.entries().enumerate() {
        prop_assert_eq!(entry, image.entry(i));
        match entry {
            Ok((id, blob)) => {
                let inside = blob.as_ptr_range();
                prop_assert!(region.start <= inside.start && inside.end <= region.end);
                entries.push((id, blob));
            }
            Err(e) => prop_assert_eq!(e, ImageError::OutOfBounds),
        }
    }
    prop_assert_eq!(image.entry(image.len()), Err(ImageError::Missing));
    if entries.len() < image.len() {
        return Ok(());
    }
    for &(id, _) in &entries {
        let first = entries.iter().find(|(i, _)| *i == id).map(|&(_, b)| b);
        prop_assert_eq!(image.blob(id).ok(), first);
    }
    let distinct = entries
        .iter()
        .enumerate()
        .all(|(i, (id, _))| entries[..i].iter().all(|(e, _)| e != id));
    let mut buf = vec![0u8; 4096];
    match write_image(&entries, &mut buf) {
        Ok(n) => {
            prop_assert!(distinct);
            let again = Image::parse(&buf[..n]).unwrap();
            let read: Vec<_> = again.entries().map(Result::unwrap).collect();
            prop_assert_eq!(read, entries);
        }
        Err(ImageError::DuplicateId(_)) => prop_assert!(!distinct),
        Err(ImageError::BufferTooSmall { needed }) => prop_assert!(needed > buf.len()),
        Err(e) => prop_assert!(false, "writer: {e}"),
    }
    Ok(())
}

fn blobs_strategy() -> impl Strategy<Value = Vec<(u16, Vec<u8>)>> {
    proptest::collection::vec(
        (0u16..12, proptest::collection::vec(any::<u8>(), 0..24)),
        0..6,
    )
    .prop_map(|mut v| {
        // Distinct ids, as the writer demands.
        let mut seen = Vec::new();
        v.retain(|(id, _)| {
            let new = !seen.contains(id);
            seen.push(*id);
            new
        });
        v
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(FUZZ_CASES))]

    /// Valid images with one header or table field mutated (CRC recomputed in most cases so the
    /// mutation gets past it).
    #[test]
    fn fuzz_structured_images(blobs in blobs_strategy(), m in mutation(), fix_crc in prop::bool::weighted(0.9)) {
        let mut image = write(&blobs, 0).unwrap();
        if matches!(m, Mutation::None) {
            prop_assert_eq!(&image, &old_host_layout(&blobs));
            let parsed = Image::parse(&image).unwrap();
            let read: Vec<_> = parsed.entries().map(Result::unwrap).collect();
            prop_assert_eq!(read, entries_of(&blobs));
        }
        mutate(&mut image, &m, fix_crc);
        check_reader(&image)?;
    }

    /// Random bytes, half of them behind a valid magic and version with a table CRC that matches.
    #[test]
    fn fuzz_raw_bytes(
        mut bytes in proptest::collection::vec(any::<u8>(), 0..160),
        count in 0u16..6,
        framed in any::<bool>(),
    ) {
        if framed && bytes.len() >= HEADER_LEN {
            bytes[..4].copy_from_slice(&MAGIC);
            bytes[4..6].copy_from_slice(&1u16.to_le_bytes());
            bytes[6..8].copy_from_slice(&count.to_le_bytes());
            mutate(&mut bytes, &Mutation::None, true);
        }
        check_reader(&bytes)?;
    }
}
