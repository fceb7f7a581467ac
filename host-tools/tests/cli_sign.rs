//! Signed images with the real tool: `tcomp keygen` makes a key pair at test time (the secret
//! readable by its owner only), `tcomp image --sign` appends the signature, `tcomp inspect` names
//! the signer and verifies against `--key` (and fails the command when it does not verify), and
//! the unit's block file is the public key's 32 bytes.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::path::Path;
use std::process::{Command, Output};
use tcomp_core::image::Image;
use tcomp_core::image::sign::{self, KeyId, KeyStore};

fn tcomp(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_tcomp"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// A fitted blob for the IFOG description's channel 0 (small and quick to fit).
fn setup(dir: &Path) {
    let board = Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware/descriptions/ifog1.toml");
    std::fs::copy(board, dir.join("b.toml")).unwrap();
    let out = tcomp(
        dir,
        &[
            "simulate",
            "--preset",
            "ifog-shupe",
            "--out",
            "sim",
            "--seed",
            "3",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = tcomp(
        dir,
        &[
            "fit",
            "--data",
            "sim/train.csv",
            "--target",
            "gyro_dph",
            "--reference",
            "ref_dph",
            "--feature",
            "t_coil_c",
            "--method",
            "poly3",
            "--sensor",
            "ifog",
            "--axis",
            "x",
            "--unit",
            "deg/h",
            "--out",
            "m.tcm",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn keygen_sign_and_inspect() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    setup(d);
    for prefix in ["station", "rogue"] {
        let out = tcomp(d, &["keygen", "--out", prefix]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt as _;
        let mode = std::fs::metadata(d.join("station.key"))
            .unwrap()
            .permissions()
            .mode();
        assert_eq!(
            mode & 0o077,
            0,
            "the secret key is readable by its owner only"
        );
    }
    // A key is never overwritten.
    let before = std::fs::read(d.join("station.key")).unwrap();
    let out = tcomp(d, &["keygen", "--out", "station"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("exists"));
    assert_eq!(std::fs::read(d.join("station.key")).unwrap(), before);

    let otp = std::fs::read(d.join("station.otp")).unwrap();
    assert_eq!(otp.len(), 32);
    let id = KeyId::of(otp.as_slice().try_into().unwrap()).to_string();

    let image_args = |sign: Option<&str>, out: &str| {
        let mut a = vec![
            "image",
            "--board",
            "b.toml",
            "--serial",
            "0x7C00001",
            "--model",
            "0=m.tcm",
        ];
        if let Some(k) = sign {
            a.extend(["--sign", k]);
        }
        a.extend(["--created", "0", "--out"]);
        a.push(out);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let run = |args: Vec<String>| {
        let refs: Vec<&str> = args.iter().map(String::as_str).collect();
        tcomp(d, &refs)
    };
    let out = run(image_args(Some("station.key"), "signed.bin"));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains(&format!("signed by key {id}")));
    let out = run(image_args(None, "plain.bin"));
    assert!(out.status.success());
    let (signed, plain) = (
        std::fs::read(d.join("signed.bin")).unwrap(),
        std::fs::read(d.join("plain.bin")).unwrap(),
    );
    // The signed file is the same image plus the 80-byte block, and it verifies with the core.
    assert_eq!(&signed[..plain.len()], &plain[..]);
    assert_eq!(signed.len(), plain.len() + sign::BLOCK_LEN);
    assert_eq!(Image::parse(&signed).unwrap().byte_len(), plain.len());
    assert_eq!(
        sign::verify(&signed, KeyStore(&otp)).unwrap().to_string(),
        id
    );

    // inspect: who signed, and whether it verifies.
    let out = tcomp(d, &["inspect", "signed.bin"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(&format!("signed by key {id} (not verified")),
        "{text}"
    );
    let out = tcomp(d, &["inspect", "signed.bin", "--key", "station.pub"]);
    assert!(out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stdout).contains(&format!("signed by key {id}: verified"))
    );
    let out = tcomp(
        d,
        &["inspect", "signed.bin", "--key", "rogue.pub", "--json"],
    );
    assert_eq!(out.status.code(), Some(1));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["signature"]["key_id"], id);
    assert_eq!(v["signature"]["verified"], false);
    assert!(String::from_utf8_lossy(&out.stderr).contains("does not verify"));
    let out = tcomp(d, &["inspect", "plain.bin", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["signature"]["signed"], false);
    // Both keys given (a unit's key store with a rotation): verifies.
    let out = tcomp(
        d,
        &[
            "inspect",
            "signed.bin",
            "--key",
            "rogue.pub",
            "--key",
            "station.pub",
        ],
    );
    assert!(out.status.success());
    // The image command's JSON names the signer.
    let mut args = image_args(Some("rogue.key"), "rogue.bin");
    args.push("--json".into());
    let out = run(args);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rogue_otp = std::fs::read(d.join("rogue.otp")).unwrap();
    assert_eq!(
        v["signer"],
        KeyId::of(rogue_otp.as_slice().try_into().unwrap()).to_string()
    );
}
