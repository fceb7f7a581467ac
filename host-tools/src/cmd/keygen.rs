//! `tcomp keygen --out PREFIX`: an Ed25519 key pair for signing calibration images
//! (`tcomp image --sign PREFIX.key`), and the block a factory provisions units with.
//!
//! Three files, none overwritten: `PREFIX.key`, the secret key (a text line, the file readable by
//! its owner only: it stays at the calibration station and never enters a repository);
//! `PREFIX.pub`, the public key (a text line, for `tcomp inspect --key`); `PREFIX.otp`, the same
//! public key as the 32 raw bytes a unit's key store holds — one STM32F407 OTP block, or the
//! QEMU board's `KEYS` region. Text lines name what they hold (`tcomp-ed25519-secret …`,
//! `tcomp-ed25519-public …`), so a public key given where a secret one is expected, or the
//! reverse, is refused with that reason instead of silently signing with the wrong bytes.
//!
//! The key comes from the operating system's generator (`rand`'s thread generator, seeded from
//! it); the key id printed is the one images and boot reports carry
//! (`tcomp_core::image::sign::KeyId`).

use anyhow::{Context, bail};
use clap::Args as ClapArgs;
use rand::RngExt as _;
use std::path::{Path, PathBuf};
use tcomp_core::image::sign::{self, KeyId, PUBLIC_KEY_LEN, SECRET_KEY_LEN};

/// The first word of a secret-key file.
const SECRET_TAG: &str = "tcomp-ed25519-secret";
/// The first word of a public-key file.
const PUBLIC_TAG: &str = "tcomp-ed25519-public";

/// Arguments of `tcomp keygen`.
#[derive(ClapArgs)]
pub struct Args {
    /// Where to write: PREFIX.key (secret), PREFIX.pub (public), PREFIX.otp (the 32-byte block
    /// a unit is provisioned with). Existing files are not overwritten.
    #[arg(long, value_name = "PREFIX")]
    pub out: PathBuf,
}

fn with_ext(prefix: &Path, ext: &str) -> PathBuf {
    let mut s = prefix.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// Reads a key file written by `tcomp keygen`: `TAG` and 64 hex digits. `option` names the
/// argument in errors.
fn read_tagged(path: &Path, tag: &str, other: &str, option: &str) -> anyhow::Result<[u8; 32]> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{option} {}: cannot read it", path.display()))?;
    let mut words = text.split_whitespace();
    let (first, digits) = (words.next(), words.next());
    if first == Some(other) {
        bail!(
            "{option} {}: this is a {} key, not a {} key",
            path.display(),
            if other == SECRET_TAG {
                "secret"
            } else {
                "public"
            },
            if tag == SECRET_TAG {
                "secret"
            } else {
                "public"
            }
        );
    }
    let (Some(t), Some(digits), None) = (first, digits, words.next()) else {
        bail!(
            "{option} {}: not a key file of `tcomp keygen` (one line: `{tag}` and 64 hex digits)",
            path.display()
        );
    };
    if t != tag || digits.len() != 64 || !digits.is_ascii() {
        bail!(
            "{option} {}: not a key file of `tcomp keygen` (one line: `{tag}` and 64 hex digits)",
            path.display()
        );
    }
    let mut key = [0u8; 32];
    for (i, k) in key.iter_mut().enumerate() {
        *k = u8::from_str_radix(&digits[2 * i..2 * i + 2], 16).with_context(|| {
            format!(
                "{option} {}: `{}` is not hex",
                path.display(),
                &digits[2 * i..2 * i + 2]
            )
        })?;
    }
    Ok(key)
}

/// The secret key of `--sign FILE`.
pub fn read_secret(path: &Path) -> anyhow::Result<[u8; SECRET_KEY_LEN]> {
    read_tagged(path, SECRET_TAG, PUBLIC_TAG, "--sign")
}

/// The public key of `--key FILE`.
pub fn read_public(path: &Path) -> anyhow::Result<[u8; PUBLIC_KEY_LEN]> {
    read_tagged(path, PUBLIC_TAG, SECRET_TAG, "--key")
}

/// Writes `bytes` to a new file (never over an existing one), readable by its owner only when
/// `private`.
fn create(path: &Path, bytes: &[u8], private: bool) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    if private {
        use std::os::unix::fs::OpenOptionsExt as _;
        options.mode(0o600);
    }
    #[cfg(not(unix))]
    let _ = private;
    let mut f = options
        .open(path)
        .with_context(|| format!("--out: cannot create {}", path.display()))?;
    f.write_all(bytes)
        .with_context(|| format!("--out: writing {}", path.display()))
}

/// Runs the command.
pub fn run(args: &Args) -> anyhow::Result<()> {
    let paths = ["key", "pub", "otp"].map(|e| with_ext(&args.out, e));
    for p in &paths {
        if p.exists() {
            bail!(
                "--out {}: {} exists; a key is never overwritten",
                args.out.display(),
                p.display()
            );
        }
    }
    if let Some(dir) = paths[0].parent().filter(|d| !d.as_os_str().is_empty())
        && !dir.is_dir()
    {
        bail!(
            "--out {}: the directory {} does not exist",
            args.out.display(),
            dir.display()
        );
    }
    let mut secret = [0u8; SECRET_KEY_LEN];
    rand::rng().fill(&mut secret[..]);
    let public = sign::public_key(&secret);
    let [key_path, pub_path, otp_path] = &paths;
    create(
        key_path,
        format!("{SECRET_TAG} {}\n", hex(&secret)).as_bytes(),
        true,
    )?;
    // The secret is written; a failure below leaves it (and says so) rather than losing it.
    create(
        pub_path,
        format!("{PUBLIC_TAG} {}\n", hex(&public)).as_bytes(),
        false,
    )?;
    create(otp_path, &public, false)?;
    outln!(
        "key {}: secret {} (keep it at the calibration station), public {}, unit key block {}",
        KeyId::of(&public),
        key_path.display(),
        pub_path.display(),
        otp_path.display()
    );
    Ok(())
}
