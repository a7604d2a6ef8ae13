//! The Falcon's runtime packets (Novint firmware): 16 bytes each way,
//! `<` … `>`, three signed 16-bit values in nibbles offset by `'A'`, least
//! significant nibble first, then one flag byte and one unused byte.
//!
//! This module owns the byte layout only: [`encode_command`] and
//! [`decode_reply`] (and their mirror images, which the emulator uses), and
//! [`PacketReader`], which finds whole packets in a byte stream that may
//! carry garbage or arrive in pieces. It never allocates and never touches
//! a transport.

/// Bytes in a packet, each way.
pub const PACKET_LEN: usize = 16;
pub const START: u8 = b'<';
pub const END: u8 = b'>';
/// Each nibble travels as `nibble + 'A'`.
const NIBBLE_BASE: u8 = b'A';
/// Byte 13, host → device.
pub const FLAG_HOMING: u8 = 0x01;
pub const LED_GREEN: u8 = 0x02;
pub const LED_BLUE: u8 = 0x04;
pub const LED_RED: u8 = 0x08;
/// Byte 13, device → host: bits 4–6 are the per-axis homed flags.
pub const HOMED_SHIFT: u8 = 4;
pub const ALL_HOMED: u8 = 0b111;

/// What the host sends: three motor commands and the flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CommandPacket {
    pub motor: [i16; 3],
    /// Homing mode (bit 0) and LEDs (`LED_*`).
    pub flags: u8,
}

/// What the device replies: three encoder counts, grip buttons, homed flags.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ReplyPacket {
    pub encoder: [i16; 3],
    /// Grip buttons, bits 0–3.
    pub buttons: u8,
    /// Per-axis homed flags, bits 0–2 (bit i = axis i).
    pub homed: u8,
}

impl ReplyPacket {
    /// The device is homed when all three axes are.
    pub fn is_homed(&self) -> bool {
        self.homed & ALL_HOMED == ALL_HOMED
    }
}

fn put_i16(out: &mut [u8], v: i16) {
    let u = v as u16;
    for (i, b) in out.iter_mut().take(4).enumerate() {
        *b = NIBBLE_BASE + ((u >> (4 * i)) & 0xF) as u8;
    }
}

fn get_i16(bytes: &[u8]) -> Option<i16> {
    let mut u: u16 = 0;
    for (i, &b) in bytes.iter().take(4).enumerate() {
        let n = b.checked_sub(NIBBLE_BASE).filter(|n| *n < 16)?;
        u |= u16::from(n) << (4 * i);
    }
    Some(u as i16)
}

fn frame(values: [i16; 3], flag_byte: u8) -> [u8; PACKET_LEN] {
    let mut p = [NIBBLE_BASE; PACKET_LEN];
    p[0] = START;
    for (k, v) in values.into_iter().enumerate() {
        put_i16(&mut p[1 + 4 * k..5 + 4 * k], v);
    }
    p[13] = flag_byte;
    p[15] = END;
    p
}

/// The three values and the raw flag value of a well-formed packet.
fn unframe(p: &[u8; PACKET_LEN]) -> Option<([i16; 3], u8)> {
    if p[0] != START || p[15] != END {
        return None;
    }
    let mut v = [0i16; 3];
    for (k, out) in v.iter_mut().enumerate() {
        *out = get_i16(&p[1 + 4 * k..5 + 4 * k])?;
    }
    // Byte 13 carries at most seven bits above 'A'; byte 14 is unused but
    // never a marker in a well-formed packet.
    let flags = p[13].checked_sub(NIBBLE_BASE).filter(|f| *f < 0x80)?;
    if p[14] == START || p[14] == END {
        return None;
    }
    Some((v, flags))
}

/// Host → device.
pub fn encode_command(c: &CommandPacket) -> [u8; PACKET_LEN] {
    frame(c.motor, NIBBLE_BASE + (c.flags & 0x0F))
}

/// Device → host (`None` when the bytes are not a valid reply).
pub fn decode_reply(p: &[u8; PACKET_LEN]) -> Option<ReplyPacket> {
    let (encoder, flags) = unframe(p)?;
    Some(ReplyPacket {
        encoder,
        buttons: flags & 0x0F,
        homed: (flags >> HOMED_SHIFT) & ALL_HOMED,
    })
}

/// The emulator's side: device → host.
pub fn encode_reply(r: &ReplyPacket) -> [u8; PACKET_LEN] {
    let flags = (r.buttons & 0x0F) | ((r.homed & ALL_HOMED) << HOMED_SHIFT);
    frame(r.encoder, NIBBLE_BASE + flags)
}

/// The emulator's side: host → device.
pub fn decode_command(p: &[u8; PACKET_LEN]) -> Option<CommandPacket> {
    let (motor, flags) = unframe(p)?;
    if flags > 0x0F {
        return None;
    }
    Some(CommandPacket { motor, flags })
}

/// What [`PacketReader`] has thrown away.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ReaderStats {
    /// Candidates that started with `<` but were not a valid packet, and
    /// runs of bytes outside any packet.
    pub bad_packets: u64,
    /// Bytes discarded while resynchronising.
    pub discarded_bytes: u64,
}

/// Finds whole packets in a byte stream: buffers partial packets, skips
/// garbage up to the next `<`, and rejects candidates that do not end in
/// `>` or carry bytes outside the nibble alphabet. Fixed capacity: bytes
/// beyond it are dropped (and counted), never allocated for.
pub struct PacketReader {
    buf: [u8; Self::CAPACITY],
    len: usize,
    pub stats: ReaderStats,
    /// Inside a run of discarded bytes (counted once as a bad packet).
    in_garbage: bool,
}

impl Default for PacketReader {
    fn default() -> Self {
        Self::new()
    }
}

impl PacketReader {
    pub const CAPACITY: usize = 512;

    pub fn new() -> PacketReader {
        PacketReader {
            buf: [0; Self::CAPACITY],
            len: 0,
            stats: ReaderStats::default(),
            in_garbage: false,
        }
    }

    /// Bytes buffered, not yet part of a packet.
    pub fn buffered(&self) -> usize {
        self.len
    }

    /// Forget what is buffered (after a purge).
    pub fn clear(&mut self) {
        self.len = 0;
        self.in_garbage = false;
    }

    /// Add received bytes.
    pub fn push(&mut self, bytes: &[u8]) {
        let room = Self::CAPACITY - self.len;
        let n = bytes.len().min(room);
        self.buf[self.len..self.len + n].copy_from_slice(&bytes[..n]);
        self.len += n;
        if n < bytes.len() {
            self.stats.discarded_bytes += (bytes.len() - n) as u64;
            self.stats.bad_packets += 1;
        }
    }

    fn discard(&mut self, n: usize) {
        self.buf.copy_within(n..self.len, 0);
        self.len -= n;
    }

    fn garbage(&mut self, n: usize) {
        if n == 0 {
            return;
        }
        self.stats.discarded_bytes += n as u64;
        if !self.in_garbage {
            self.stats.bad_packets += 1;
            self.in_garbage = true;
        }
        self.discard(n);
    }

    /// The next whole, well-formed packet, if one is buffered.
    pub fn next_packet(&mut self) -> Option<[u8; PACKET_LEN]> {
        loop {
            let start = self.buf[..self.len].iter().position(|&b| b == START);
            let Some(start) = start else {
                let n = self.len;
                self.garbage(n);
                return None;
            };
            self.garbage(start);
            if self.len < PACKET_LEN {
                return None;
            }
            let mut p = [0u8; PACKET_LEN];
            p.copy_from_slice(&self.buf[..PACKET_LEN]);
            if unframe(&p).is_some() {
                self.discard(PACKET_LEN);
                self.in_garbage = false;
                return Some(p);
            }
            // Not a packet: drop this '<' and look for the next one.
            self.stats.bad_packets += 1;
            self.in_garbage = true;
            self.stats.discarded_bytes += 1;
            self.discard(1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_known_command_encodes_to_known_bytes() {
        let c = CommandPacket {
            motor: [0, 1, -1],
            flags: FLAG_HOMING | LED_RED,
        };
        assert_eq!(&encode_command(&c), b"<AAAABAAAPPPPJA>");
        let c = CommandPacket {
            motor: [0x1234, -4095, 4095],
            flags: LED_BLUE | FLAG_HOMING,
        };
        // 0x1234 -> nibbles 4,3,2,1; -4095 = 0xF001 -> 1,0,0,F; 4095 = 0x0FFF -> F,F,F,0.
        assert_eq!(&encode_command(&c), b"<EDCBBAAPPPPAFA>");
    }

    #[test]
    fn a_known_reply_decodes() {
        // Encoders 16, -2, 0x7FFF; buttons 0b0101; all homed: 0x75 + 'A' = 0xB6.
        let mut p = *b"<AB\x41\x41OPPPPPPHA\x41>";
        p[3] = b'A';
        p[4] = b'A';
        p[13] = 0x41 + 0x75;
        let r = decode_reply(&p).unwrap();
        assert_eq!(r.encoder, [16, -2, 0x7FFF]);
        assert_eq!(r.buttons, 0b0101);
        assert_eq!(r.homed, 0b111);
        assert!(r.is_homed());
    }

    #[test]
    fn round_trips_over_the_whole_range() {
        for v in [i16::MIN, -4095, -1, 0, 1, 325, 4095, i16::MAX] {
            for flags in 0..16u8 {
                let c = CommandPacket {
                    motor: [v, v.wrapping_neg(), v / 3],
                    flags,
                };
                assert_eq!(decode_command(&encode_command(&c)), Some(c));
            }
            for homed in 0..8u8 {
                let r = ReplyPacket {
                    encoder: [v, -7, v / 2],
                    buttons: homed * 2 % 16,
                    homed,
                };
                assert_eq!(decode_reply(&encode_reply(&r)), Some(r));
                assert_eq!(r.is_homed(), homed == 7);
            }
        }
    }

    #[test]
    fn the_reader_resyncs_after_garbage_and_partial_reads() {
        let a = encode_reply(&ReplyPacket {
            encoder: [1, 2, 3],
            ..Default::default()
        });
        let b = encode_reply(&ReplyPacket {
            encoder: [-4, 5, -6],
            buttons: 1,
            homed: 7,
        });
        let mut r = PacketReader::new();
        // Garbage, a truncated packet, then a whole one split in three pieces.
        r.push(b"\x00\x13xx");
        r.push(&a[..9]);
        assert_eq!(r.next_packet(), None);
        r.push(&b[..5]);
        assert_eq!(r.next_packet(), None);
        r.push(&b[5..12]);
        r.push(&b[12..]);
        assert_eq!(r.next_packet(), Some(b));
        assert_eq!(r.next_packet(), None);
        assert_eq!(r.buffered(), 0);
        assert!(r.stats.bad_packets >= 2, "{:?}", r.stats);
        // Clean packets back to back.
        r.push(&a);
        r.push(&b);
        assert_eq!(r.next_packet(), Some(a));
        assert_eq!(r.next_packet(), Some(b));
    }

    #[test]
    fn a_garbled_byte_rejects_the_packet() {
        let mut p = encode_reply(&ReplyPacket::default());
        p[6] = b'z';
        assert_eq!(decode_reply(&p), None);
        let mut r = PacketReader::new();
        r.push(&p);
        assert_eq!(r.next_packet(), None);
        assert_eq!(r.stats.bad_packets, 1);
        // The next good packet still comes through.
        let good = encode_reply(&ReplyPacket::default());
        r.push(&good);
        assert_eq!(r.next_packet(), Some(good));
    }

    #[test]
    fn overflow_is_counted_not_allocated() {
        let mut r = PacketReader::new();
        r.push(&[b'x'; PacketReader::CAPACITY + 10]);
        assert_eq!(r.stats.discarded_bytes, 10);
        assert_eq!(r.next_packet(), None);
        assert_eq!(r.buffered(), 0);
    }

    proptest::proptest! {
        /// Any 16 bytes decode to a packet or to `None`; any stream, in any
        /// pieces, yields only well-formed packets, and every byte pushed is
        /// a packet's, counted as discarded, or still buffered.
        #[test]
        fn any_bytes_decode_or_are_refused_and_every_byte_is_accounted_for(
            stream in proptest::collection::vec(
                proptest::prop_oneof![
                    proptest::sample::select(b"<>AP@Q".to_vec()),
                    proptest::arbitrary::any::<u8>(),
                ],
                0..1500,
            ),
            piece in 1usize..700,
        ) {
            for p in stream.chunks_exact(PACKET_LEN) {
                let p: &[u8; PACKET_LEN] = p.try_into().unwrap();
                if let Some(r) = decode_reply(p) {
                    proptest::prop_assert_eq!(&encode_reply(&r)[..14], &p[..14]);
                }
                if let Some(c) = decode_command(p) {
                    proptest::prop_assert_eq!(&encode_command(&c)[..14], &p[..14]);
                }
            }
            let mut r = PacketReader::new();
            let mut packets = 0;
            for bytes in stream.chunks(piece) {
                r.push(bytes);
                while let Some(p) = r.next_packet() {
                    proptest::prop_assert!(decode_reply(&p).is_some());
                    packets += 1;
                }
            }
            proptest::prop_assert_eq!(
                stream.len() as u64,
                packets * PACKET_LEN as u64 + r.stats.discarded_bytes + r.buffered() as u64
            );
        }
    }
}
