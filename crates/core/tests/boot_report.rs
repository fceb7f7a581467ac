//! The boot report shares the serial link with the data frames: it round-trips, a data-only reader
//! skips it without losing a frame, and a damaged report is dropped like a damaged frame.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use tcomp_core::frame::{
    BootReport, ChannelOutput, ChannelState, Decoder, Frame, Item, MAX_FRAME_LEN, boot_len,
    image_state, status,
};

fn report() -> BootReport {
    let mut r = BootReport::default();
    r.sequence = 7;
    r.unit_serial = 0x7C0_0001;
    r.image_serial = 0x7C0_0001;
    r.board_hash = 0x90e2_b349_2235_77da;
    r.image_crc = 0xdead_beef;
    r.image_version = 2;
    r.image_state = image_state::OK;
    r.flags = 1;
    r.stack_peak = 9_504;
    r.worst_task = 0x0012_3456;
    let ch: Vec<ChannelState> = (0..6)
        .map(|id| ChannelState {
            id,
            state: (id % 3) as u8,
        })
        .collect();
    r.set_channels(&ch);
    r
}

fn data(seq: u32) -> Vec<u8> {
    let c = [ChannelOutput {
        value: 1.5 * f64::from(seq),
        status: status::OK,
    }; 6];
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = Frame::new(seq, u64::from(seq), 200, &c)
        .encode(&mut buf)
        .unwrap();
    buf[..n].to_vec()
}

fn encoded(r: &BootReport) -> Vec<u8> {
    let mut buf = [0u8; 128];
    let n = r.encode(&mut buf).unwrap();
    assert_eq!(n, boot_len(r.channels().len()));
    assert!(r.encode(&mut buf[..n - 1]).is_none());
    buf[..n].to_vec()
}

#[test]
fn data_frames_and_reports_interleave() {
    let r = report();
    let mut stream = data(5);
    stream.extend(encoded(&r));
    stream.extend(data(6));
    stream.extend(encoded(&r));
    stream.extend(data(7));

    let mut items = Vec::new();
    let mut d = Decoder::new();
    d.feed_items(&stream, |i| items.push(i));
    assert_eq!(items.len(), 5);
    assert_eq!(items[1], Item::Boot(r));
    assert!(matches!(items[4], Item::Data(f) if f.sequence == 7));
    assert_eq!(d.boot_reports(), 2);

    // A reader of data frames only sees every frame, nothing skipped, lost or corrupt.
    let mut frames = Vec::new();
    let mut d = Decoder::new();
    d.feed(&stream, |f| frames.push(f.sequence));
    assert_eq!(frames, [5, 6, 7]);
    let s = d.stats();
    assert_eq!((s.lost, s.corrupt, s.skipped), (0, 0, 0));
}

#[test]
fn a_damaged_report_is_dropped_and_the_next_frame_kept() {
    let good = encoded(&report());
    for at in 2..good.len() {
        let mut bad = good.clone();
        bad[at] ^= 0x04;
        let mut stream = bad;
        stream.extend(data(9));
        let mut items = Vec::new();
        Decoder::new().feed_items(&stream, |i| items.push(i));
        assert!(
            items
                .iter()
                .any(|i| matches!(i, Item::Data(f) if f.sequence == 9)),
            "flip at {at}"
        );
        assert!(
            !items.iter().any(|i| *i == Item::Boot(report())),
            "flip at {at}"
        );
    }
}
