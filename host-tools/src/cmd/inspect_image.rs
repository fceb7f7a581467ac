//! `tcomp inspect IMAGE`: the calibration image's header, its board's thermometers and channel
//! table, and what every channel will run at boot — the model (sensor, unit, features, provenance)
//! or `NO_MODEL` and why — decided by the same checks the firmware makes (`Image::parse`, the
//! blob's own decode, `ChannelRow::accepts`).
//!
//! Every string taken from the image goes through [`crate::output::printable`]: an image is a file from
//! elsewhere, and its strings must not drive the terminal.
use serde_json::{Value, json};
use std::path::Path;
use tcomp_core::image::sign::{self, KeyStore, SignatureError};
use tcomp_core::image::{ChannelRow, Image, Source, ThermKind};

use crate::output::printable::text;

/// What channel `row` will run: `Ok(description)` or `Err(reason for NO_MODEL)`.
fn verdict(image: &Image<'_>, row: &ChannelRow<'_>) -> Result<Value, String> {
    let blob = image.blob(row.id).map_err(|e| e.to_string())?;
    let m = tcomp_train::blob_io::decode(Path::new("blob"), blob).map_err(|e| e.to_string())?;
    row.accepts(&m.meta, m.program.inputs.iter().map(|s| &**s))
        .map_err(|e| format!("the model does not belong on this channel: {e:?}"))?;
    Ok(json!({
        "sensor": format!("{:?}", m.meta.sensor),
        "axis": text(m.meta.axis),
        "unit": text(m.meta.unit),
        "method": text(m.meta.method),
        "inputs": m.program.inputs.iter().map(|s| text(s)).collect::<Vec<_>>(),
        "features": m.program.feature_exprs.iter().map(|s| text(s)).collect::<Vec<_>>(),
        "centers": m.rbf.centers.len(),
        "bytes": blob.len(),
    }))
}

fn source(s: Source) -> String {
    match s {
        Source::Counter(n) => format!("counter {n}"),
        Source::Sample(n) => format!("sample {n}"),
    }
}

fn therm_kind(k: ThermKind) -> String {
    match k {
        ThermKind::Rtd { r0, a, b } => format!("RTD r0 {r0} Ω a {a:e} b {b:e}"),
        ThermKind::Ntc { r0, beta, t0_k } => format!("NTC r0 {r0} Ω beta {beta} K t0 {t0_k} K"),
        ThermKind::Digital { scale, offset_c } => {
            format!("digital {scale} °C/LSB + {offset_c} °C")
        }
    }
}

/// The signature: who signed (key id), and whether it verifies against the given keys (`null`
/// when none was given).
fn signature(bytes: &[u8], keys: &[[u8; 32]]) -> Value {
    let block = match sign::block(bytes) {
        Ok((_, Some(b))) => b,
        Ok((_, None)) => return json!({"signed": false, "key_id": null, "verified": null}),
        Err(e) => {
            return json!({"signed": true, "key_id": null, "verified": false, "reason": e.to_string()});
        }
    };
    if keys.is_empty() {
        return json!({"signed": true, "key_id": block.key.to_string(), "verified": null});
    }
    let store = keys.concat();
    let (verified, reason) = match sign::verify(bytes, KeyStore(&store)) {
        Ok(_) => (true, None),
        Err(e @ (SignatureError::UnknownKey(_) | SignatureError::BadSignature(_))) => {
            (false, Some(e.to_string()))
        }
        Err(e) => (false, Some(e.to_string())),
    };
    json!({
        "signed": true,
        "key_id": block.key.to_string(),
        "verified": verified,
        "reason": reason,
        "keys": keys.iter().map(|k| sign::KeyId::of(k).to_string()).collect::<Vec<_>>(),
    })
}

/// The whole image as JSON (what `--json` prints; the human summary is drawn from it).
fn describe(file: &Path, bytes: &[u8], image: &Image<'_>, keys: &[[u8; 32]]) -> Value {
    let header = image.header().map(|h| {
        json!({
            "serial": h.serial,
            "board_hash": format!("{:016x}", h.board_hash),
            "created": h.created,
            "tool": text(h.tool),
            "crc": format!("{:08x}", h.crc),
        })
    });
    let thermometers: Vec<Value> = (0..image.n_thermometers())
        .filter_map(|i| image.thermometer(i))
        .map(|t| {
            json!({"name": text(t.name), "adc": t.adc, "input": t.input, "kind": therm_kind(t.kind)})
        })
        .collect();
    let channels: Vec<Value> = (0..image.n_channels())
        .filter_map(|i| image.channel(i))
        .map(|row| {
            let entry = (0..image.len()).find(|&i| image.entry(i).is_ok_and(|(id, _)| id == row.id));
            let prov = entry.and_then(|i| image.provenance(i)).map(|p| {
                json!({
                    "data": text(p.data),
                    "data_hash": format!("{:016x}", p.data_hash),
                    "window_s": [p.window[0], p.window[1]],
                    "method": text(p.method),
                    "blob_crc": entry.and_then(|i| image.entry_crc(i)).map(|c| format!("{c:08x}")),
                })
            });
            let (runs, reason) = match verdict(image, &row) {
                Ok(model) => (Some(model), None),
                Err(why) => (None, Some(why)),
            };
            json!({
                "id": row.id,
                "name": text(row.name),
                "sensor": format!("{:?}", row.sensor),
                "axis": text(row.axis),
                "unit": text(row.unit),
                "source": source(row.source),
                "scale": row.scale,
                "inputs": row.inputs().iter().map(|i| json!({
                    "column": text(i.name),
                    "thermometer": image.thermometer(usize::from(i.thermometer)).map(|t| text(t.name)),
                })).collect::<Vec<_>>(),
                "provenance": prov,
                "model": runs,
                "no_model": reason,
            })
        })
        .collect();
    json!({
        "file": file.display().to_string(),
        "bytes": bytes.len(),
        "version": image.version(),
        "header": header,
        "signature": signature(bytes, keys),
        "thermometers": thermometers,
        "channels": channels,
        "entries": image.len(),
    })
}

/// Prints the image in `bytes` (already known to start with the image magic).
pub fn run(file: &Path, bytes: &[u8], json_out: bool, keys: &[[u8; 32]]) -> anyhow::Result<()> {
    let image = Image::parse(bytes)
        .map_err(|e| anyhow::anyhow!("{}: not a valid calibration image: {e}", file.display()))?;
    let v = describe(file, bytes, &image, keys);
    let failed = v["signature"]["verified"] == Value::Bool(false);
    let verdict = || {
        anyhow::anyhow!(
            "{}: the signature does not verify against --key: {}",
            file.display(),
            v["signature"]["reason"].as_str().unwrap_or("")
        )
    };
    if json_out {
        outln!(
            "{}",
            crate::output::printable::json(&serde_json::to_string_pretty(&v)?)
        );
        return if failed { Err(verdict()) } else { Ok(()) };
    }
    outln!(
        "{}: valid tcomp calibration image, format version {}, {} bytes, {} models",
        file.display(),
        image.version(),
        bytes.len(),
        image.len()
    );
    if let Some(h) = &v["header"].as_object() {
        outln!(
            "unit serial  {}   board hash {}   created {} (s since 1970 UTC)   tool {}   crc {}",
            h["serial"].as_u64().unwrap_or(0),
            h["board_hash"].as_str().unwrap_or(""),
            h["created"].as_u64().unwrap_or(0),
            h["tool"].as_str().unwrap_or(""),
            h["crc"].as_str().unwrap_or("")
        );
    }
    for (i, t) in v["thermometers"]
        .as_array()
        .into_iter()
        .flatten()
        .enumerate()
    {
        outln!(
            "thermometer {i:>2} {:<16} adc {} input {}  {}",
            t["name"].as_str().unwrap_or(""),
            t["adc"].as_u64().unwrap_or(0),
            t["input"].as_u64().unwrap_or(0),
            t["kind"].as_str().unwrap_or("")
        );
    }
    outln!(
        "{:>4} {:<10} {:<10} {:<5} {:<7} {:<10} {}",
        "id",
        "name",
        "sensor",
        "axis",
        "unit",
        "source",
        "runs"
    );
    for c in v["channels"].as_array().into_iter().flatten() {
        let runs = match (&c["model"], &c["no_model"]) {
            (Value::Object(m), _) => format!(
                "model: {} [{}], {} centers, trained on {} t={}..{} s",
                m["method"].as_str().unwrap_or(""),
                m["features"]
                    .as_array()
                    .map(|f| f
                        .iter()
                        .filter_map(Value::as_str)
                        .collect::<Vec<_>>()
                        .join(", "))
                    .unwrap_or_default(),
                m["centers"],
                c["provenance"]["data"].as_str().unwrap_or("?"),
                c["provenance"]["window_s"][0],
                c["provenance"]["window_s"][1],
            ),
            (_, Value::String(why)) => format!("NO_MODEL ({why})"),
            _ => "NO_MODEL".into(),
        };
        outln!(
            "{:>4} {:<10} {:<10} {:<5} {:<7} {:<10} {}",
            c["id"].as_u64().unwrap_or(0),
            c["name"].as_str().unwrap_or(""),
            c["sensor"].as_str().unwrap_or(""),
            c["axis"].as_str().unwrap_or(""),
            c["unit"].as_str().unwrap_or(""),
            c["source"].as_str().unwrap_or(""),
            runs
        );
    }
    if image.version() == 1 {
        for (id, blob) in image.entries().flatten() {
            outln!(
                "entry        channel {id}, {} bytes (version 1: no channel table)",
                blob.len()
            );
        }
    }
    let sig = &v["signature"];
    let line = match (
        sig["signed"].as_bool(),
        sig["key_id"].as_str(),
        &sig["verified"],
    ) {
        (Some(false), ..) => "unsigned (a unit runs it only in a development build)".to_string(),
        (_, Some(id), Value::Null) => format!("signed by key {id} (not verified: give --key PUB)"),
        (_, Some(id), Value::Bool(true)) => format!("signed by key {id}: verified against --key"),
        (_, id, _) => format!(
            "signed by key {}: DOES NOT VERIFY ({})",
            id.unwrap_or("?"),
            sig["reason"].as_str().unwrap_or("")
        ),
    };
    outln!("signature    {line}");
    if failed {
        return Err(verdict());
    }
    Ok(())
}
