//! Signed images: sign and verify round trip with a key made at test time, every single-bit flip
//! of a signed image refused, another key refused, a forged key id refused, the key store's
//! empty and revoked blocks skipped, an unsigned or malformed block named as such.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::io::Read;
use tcomp_core::image::sign::{
    self, BLOCK_LEN, KeyId, KeyStore, PUBLIC_KEY_LEN, SECRET_KEY_LEN, SignatureError,
};
use tcomp_core::image::{Image, write_image};

/// A secret key from the operating system's generator, made now (no key lives in the repository).
fn fresh_key() -> [u8; SECRET_KEY_LEN] {
    let mut seed = [0u8; SECRET_KEY_LEN];
    std::fs::File::open("/dev/urandom")
        .unwrap()
        .read_exact(&mut seed)
        .unwrap();
    seed
}

fn image() -> Vec<u8> {
    let blobs: Vec<Vec<u8>> = (0..2u8)
        .map(|i| (0..300u32).map(|j| (j as u8).wrapping_mul(5) ^ i).collect())
        .collect();
    let entries: Vec<(u16, &[u8])> = blobs
        .iter()
        .enumerate()
        .map(|(i, b)| (i as u16, b.as_slice()))
        .collect();
    let mut buf = vec![0u8; 4096];
    let n = write_image(&entries, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

fn signed(image: &[u8], secret: &[u8; 32]) -> Vec<u8> {
    let mut buf = image.to_vec();
    buf.resize(image.len() + BLOCK_LEN, 0xFF);
    let n = sign::sign(&mut buf, secret).unwrap();
    assert_eq!(n, buf.len());
    buf
}

fn store(keys: &[[u8; PUBLIC_KEY_LEN]]) -> Vec<u8> {
    keys.concat()
}

#[test]
fn a_signed_image_verifies_and_names_its_key() {
    let secret = fresh_key();
    let public = sign::public_key(&secret);
    let img = image();
    let s = signed(&img, &secret);
    // Still the same image to the reader.
    assert_eq!(Image::parse(&s).unwrap().byte_len(), img.len());
    let keys = store(&[public]);
    assert_eq!(sign::verify(&s, KeyStore(&keys)), Ok(KeyId::of(&public)));
    // Unsigned: the image alone, or followed by erased flash.
    assert_eq!(
        sign::verify(&img, KeyStore(&keys)),
        Err(SignatureError::Unsigned)
    );
    let mut erased = img.clone();
    erased.resize(img.len() + 200, 0xFF);
    assert_eq!(
        sign::verify(&erased, KeyStore(&keys)),
        Err(SignatureError::Unsigned)
    );
    // Signing again replaces the block.
    let mut again = s.clone();
    sign::sign(&mut again, &secret).unwrap();
    assert_eq!(again, s, "Ed25519 signing is deterministic");
}

/// Every single-bit flip anywhere in the signed file (image and block) is refused.
#[test]
fn every_single_bit_flip_of_a_signed_image_is_refused() {
    let secret = fresh_key();
    let keys = store(&[sign::public_key(&secret)]);
    let s = signed(&image(), &secret);
    let mut flipped = s.clone();
    let mut refused = 0usize;
    for byte in 0..s.len() {
        for bit in 0..8 {
            flipped[byte] ^= 1 << bit;
            let r = sign::verify(&flipped, KeyStore(&keys));
            assert!(r.is_err(), "flip of bit {bit} of byte {byte} accepted");
            refused += 1;
            flipped[byte] ^= 1 << bit;
        }
    }
    assert_eq!(refused, 8 * s.len());
    assert!(sign::verify(&flipped, KeyStore(&keys)).is_ok());
}

#[test]
fn another_key_and_a_forged_key_id_are_refused() {
    let (ours, theirs) = (fresh_key(), fresh_key());
    let our_public = sign::public_key(&ours);
    let keys = store(&[our_public]);
    let s = signed(&image(), &theirs);
    let their_id = KeyId::of(&sign::public_key(&theirs));
    assert_eq!(
        sign::verify(&s, KeyStore(&keys)),
        Err(SignatureError::UnknownKey(their_id))
    );
    // Their signature under our key id.
    let mut forged = s.clone();
    let at = image().len();
    forged[at + 8..at + 16].copy_from_slice(&KeyId::of(&our_public).0);
    assert_eq!(
        sign::verify(&forged, KeyStore(&keys)),
        Err(SignatureError::BadSignature(KeyId::of(&our_public)))
    );
}

#[test]
fn the_key_store_skips_empty_and_revoked_blocks() {
    let (old, new) = (fresh_key(), fresh_key());
    let (old_pub, new_pub) = (sign::public_key(&old), sign::public_key(&new));
    // OTP as a factory leaves it: block 1 the first key, block 2 its successor, 3–4 empty.
    let otp = store(&[old_pub, new_pub, [0xFF; 32], [0xFF; 32]]);
    let ks = KeyStore(&otp);
    assert_eq!(ks.keys().count(), 2);
    let by_old = signed(&image(), &old);
    assert!(sign::verify(&by_old, ks).is_ok());
    // The first key revoked (its block programmed to zeros): its images are refused.
    let revoked = store(&[[0; 32], new_pub, [0xFF; 32], [0xFF; 32]]);
    assert_eq!(
        sign::verify(&by_old, KeyStore(&revoked)),
        Err(SignatureError::UnknownKey(KeyId::of(&old_pub)))
    );
    assert!(sign::verify(&signed(&image(), &new), KeyStore(&revoked)).is_ok());
    assert!(KeyStore(&[0xFF; 128]).is_empty() && KeyStore(&[0; 128]).is_empty());
}

#[test]
fn a_malformed_or_cut_block_is_named() {
    let secret = fresh_key();
    let keys = store(&[sign::public_key(&secret)]);
    let s = signed(&image(), &secret);
    let at = image().len();
    let mut wrong_version = s.clone();
    wrong_version[at + 4] = 2;
    assert_eq!(
        sign::verify(&wrong_version, KeyStore(&keys)),
        Err(SignatureError::Malformed)
    );
    assert_eq!(
        sign::verify(&s[..s.len() - 1], KeyStore(&keys)),
        Err(SignatureError::Malformed)
    );
    assert!(matches!(
        sign::verify(b"junk", KeyStore(&keys)),
        Err(SignatureError::Image(_))
    ));
}
