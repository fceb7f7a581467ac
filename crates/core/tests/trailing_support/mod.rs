//! The round trip of a model whose blob carries fields after the derived layout (format 3's masks,
//! format 4's kinds), shared by the tests of each: both decoders give the model back, and a blob cut
//! short in those fields, or with a byte after them, is refused (after resealing the CRC).

use tcomp_core::HostModel;

/// Encodes `m`, decodes it with both decoders, and checks that truncated and over-long trailing
/// fields are refused.
pub fn round_trips_and_refuses_bad_trailing_fields(m: &HostModel) {
    let mut buf = vec![0u8; 8192];
    let n = m.encode(&mut buf).unwrap();
    let bytes = &buf[..n];
    assert_eq!(&HostModel::decode(bytes).unwrap(), m);
    let mut place = None;
    HostModel::decode_into(bytes, &mut place).unwrap();
    assert_eq!(place.as_ref(), Some(m));
    for body in [&bytes[..n - 5], &[&bytes[..n - 4], &[0u8][..]].concat()[..]] {
        let mut b = body.to_vec();
        let crc = tcomp_core::blob::crc32(&b);
        b.extend_from_slice(&crc.to_le_bytes());
        assert!(HostModel::decode(&b).is_err());
    }
}
