//! Model updates over the serial link: the framed protocol ([`wire`]) and the unit's receiver
//! ([`receiver`]), both `no_std`, shared by the firmware and the host's `tcomp flash`.
//!
//! The host checks the image, then sends HELLO (the unit answers INFO: serial, active slot,
//! generation), BEGIN (length, CRC; the unit erases its inactive slot), DATA chunks of up to
//! [`wire::MAX_CHUNK`] bytes in order, and COMMIT (the unit reads the slot back, checks the CRC and
//! the image, writes the commit word, and answers RESULT). Every request is answered by ACK, NAK
//! (with a reason and, for chunks, the offset the unit expects) or RESULT; the host repeats a
//! request on a NAK it can act on or on a timeout. The unit keeps sending its output frames on
//! the same link throughout: the update frames have their own sync word, and both sides' decoders
//! skip what is not theirs.
//!
//! Where the slots lie and how a power cut is survived is [`crate::slots`]'s business.

pub mod receiver;
pub mod sender;
pub mod wire;

pub use receiver::{Receiver, Reply};
pub use sender::{Failure, Info, Sender, Status};
pub use wire::{Decoder, Kind, Packet, Reason};
