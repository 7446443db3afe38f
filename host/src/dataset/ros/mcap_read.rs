//! MCAP files read without holding them in memory: [`McapParts::scan`] walks every record of
//! one or more files (the split files of a rosbag2 folder, in order) once and reports each
//! message with its [`Location`]; [`McapParts::read`] fetches one message again from there.
//! At most one record (and one decompressed chunk) is in memory at a time, so a reader's
//! memory does not grow with the length of the recording.
//!
//! The records are parsed by the `mcap` crate ([`mcap::parse_record`]); chunks are
//! decompressed here with the `zstd` and `lz4` crates (the ones `mcap` uses), because the
//! crate's readers do not say where in a chunk a message lies. Every length is checked
//! against what is left of the file or chunk and against [`MAX_RECORD_BYTES`] before
//! anything is allocated, so a corrupt file is an error, never an abort.

use anyhow::{anyhow, bail, Context, Result};
use mcap::records::{ChunkHeader, Record};
use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Longest record accepted (and largest decompressed chunk): 64 MiB, twenty 1024x768
/// float depth images. It bounds the memory a corrupt length can make a reader take.
pub const MAX_RECORD_BYTES: u64 = 1 << 26;

/// The magic at both ends of an MCAP file.
const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";

/// Record opcodes the reader acts on (the others are skipped).
mod op {
    pub const FOOTER: u8 = 0x02;
    pub const SCHEMA: u8 = 0x03;
    pub const CHANNEL: u8 = 0x04;
    pub const MESSAGE: u8 = 0x05;
    pub const CHUNK: u8 = 0x06;
    pub const DATA_END: u8 = 0x0f;
}

/// Bytes readable at any offset from several threads at once (a file, or bytes in memory).
pub trait ReadAt: Send + Sync {
    /// Fills `buf` from `offset`; an error if the source ends first.
    fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()>;
}

impl ReadAt for std::fs::File {
    fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        std::os::unix::fs::FileExt::read_exact_at(self, buf, offset)
    }
}

impl ReadAt for Vec<u8> {
    fn read_exact_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        let start = usize::try_from(offset).unwrap_or(usize::MAX);
        let src = start
            .checked_add(buf.len())
            .and_then(|end| self.get(start..end))
            .ok_or(std::io::ErrorKind::UnexpectedEof)?;
        buf.copy_from_slice(src);
        Ok(())
    }
}

/// One MCAP file.
struct Part {
    name: PathBuf,
    bytes: Box<dyn ReadAt>,
    len: u64,
}

/// Where a message is: the file, the offset of its top-level record (a message or the
/// chunk holding it) and, inside a chunk, the offset of its record in the decompressed
/// records.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Location {
    part: u32,
    record: u64,
    in_chunk: Option<u32>,
}

/// A message as the scan meets it.
pub struct ScannedMessage<'a> {
    /// Topic of its channel.
    pub topic: &'a str,
    /// Name of its schema (message type), empty without one.
    pub schema: &'a str,
    /// Message encoding of its channel (`cdr` for ROS 2).
    pub encoding: &'a str,
    /// Log time, ns.
    pub log_time: u64,
    /// The serialized message.
    pub data: &'a [u8],
    /// Where to read it again.
    pub at: Location,
}

/// A channel: topic, schema name, message encoding.
type ChannelInfo = (String, String, String);

/// The MCAP files of one recording, in order.
pub struct McapParts {
    parts: Vec<Part>,
}

impl McapParts {
    /// Opens `files`, in the order given.
    pub fn open(files: &[PathBuf]) -> Result<McapParts> {
        let mut parts = Vec::new();
        for f in files {
            let file =
                std::fs::File::open(f).with_context(|| format!("reading {}", f.display()))?;
            let len = file.metadata()?.len();
            parts.push(Part {
                name: f.clone(),
                bytes: Box::new(file),
                len,
            });
        }
        Ok(McapParts { parts })
    }

    /// No files (a placeholder while a scan runs).
    pub fn empty() -> McapParts {
        McapParts { parts: Vec::new() }
    }

    /// One file already in memory; `name` only names it in errors.
    pub fn from_bytes(name: &Path, bytes: Vec<u8>) -> McapParts {
        let len = bytes.len() as u64;
        McapParts {
            parts: vec![Part {
                name: name.to_path_buf(),
                bytes: Box::new(bytes),
                len,
            }],
        }
    }

    /// Calls `visit` on every message of every file, in file order (records inside a chunk
    /// in their order in the chunk).
    pub fn scan(&self, mut visit: impl FnMut(ScannedMessage) -> Result<()>) -> Result<()> {
        for (k, part) in self.parts.iter().enumerate() {
            let mut walk = Walk {
                part: k as u32,
                schemas: HashMap::new(),
                channels: HashMap::new(),
            };
            walk.file(part, &mut visit).with_context(|| {
                format!(
                    "reading the MCAP file {} (truncated or corrupt?)",
                    part.name.display()
                )
            })?;
        }
        Ok(())
    }

    /// The message at `at`, as [`McapParts::scan`] reported it.
    pub fn read(&self, at: Location) -> Result<Vec<u8>> {
        let part = self
            .parts
            .get(at.part as usize)
            .ok_or_else(|| anyhow!("no MCAP file {} in this recording", at.part))?;
        let (opcode, body) = read_record(part, at.record)?
            .ok_or_else(|| anyhow!("{}: no record at {}", part.name.display(), at.record))?;
        let data = match (parse(opcode, &body)?, at.in_chunk) {
            (Record::Message { data, .. }, None) => data.into_owned(),
            (Record::Chunk { header, data }, Some(offset)) => {
                let records = decompress(&header, &data)?;
                let (opcode, body, _) = inner_record(&records, offset as usize)?
                    .ok_or_else(|| anyhow!("no record at {offset} in the chunk"))?;
                match parse(opcode, body)? {
                    Record::Message { data, .. } => data.into_owned(),
                    _ => bail!("the record at {offset} in the chunk is not a message"),
                }
            }
            _ => bail!("the record at {} is not a message", at.record),
        };
        Ok(data)
    }
}

/// The state of one file's scan: its schemas and channels by id.
struct Walk {
    part: u32,
    schemas: HashMap<u16, String>,
    channels: HashMap<u16, ChannelInfo>,
}

impl Walk {
    /// Walks the top-level records of `part` up to the end of its data section.
    fn file(
        &mut self,
        part: &Part,
        visit: &mut impl FnMut(ScannedMessage) -> Result<()>,
    ) -> Result<()> {
        let mut magic = [0u8; 8];
        if part.len < 8 || part.bytes.read_exact_at(&mut magic, 0).is_err() || &magic != MAGIC {
            bail!("not an MCAP file (no MCAP magic at the start)");
        }
        let mut at = 8;
        loop {
            let Some((opcode, len)) = record_header(part, at)? else {
                bail!("the file ends at byte {at} without a footer (truncated?)");
            };
            if matches!(opcode, op::FOOTER | op::DATA_END) {
                return Ok(());
            }
            if matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE | op::CHUNK) {
                let (_, body) = read_record(part, at)?
                    .ok_or_else(|| anyhow!("the record at byte {at} vanished"))?;
                let location = Location {
                    part: self.part,
                    record: at,
                    in_chunk: None,
                };
                self.record(opcode, &body, location, visit)
                    .with_context(|| format!("in the record at byte {at}"))?;
            }
            at += 9 + len;
        }
    }

    /// Acts on one record: keeps schemas and channels, reports messages, opens chunks.
    fn record(
        &mut self,
        opcode: u8,
        body: &[u8],
        at: Location,
        visit: &mut impl FnMut(ScannedMessage) -> Result<()>,
    ) -> Result<()> {
        match parse(opcode, body)? {
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(c) => {
                let schema =
                    match c.schema_id {
                        0 => String::new(),
                        id => self.schemas.get(&id).cloned().ok_or_else(|| {
                            anyhow!("channel {} names unknown schema {id}", c.topic)
                        })?,
                    };
                self.channels
                    .insert(c.id, (c.topic, schema, c.message_encoding));
            }
            Record::Message { header, data } => {
                let (topic, schema, encoding) = self
                    .channels
                    .get(&header.channel_id)
                    .ok_or_else(|| anyhow!("a message on unknown channel {}", header.channel_id))?;
                visit(ScannedMessage {
                    topic,
                    schema,
                    encoding,
                    log_time: header.log_time,
                    data: &data,
                    at,
                })?;
            }
            Record::Chunk { header, data } if at.in_chunk.is_none() => {
                let records = decompress(&header, &data)?;
                let mut offset = 0;
                while let Some((opcode, body, next)) = inner_record(&records, offset)? {
                    let inner = Location {
                        in_chunk: Some(offset as u32),
                        ..at
                    };
                    self.record(opcode, body, inner, visit)
                        .with_context(|| format!("at byte {offset} of the chunk"))?;
                    offset = next;
                }
            }
            Record::Chunk { .. } => bail!("a chunk inside a chunk"),
            // Other records inside a chunk are not in the format; skipped like unknown ones.
            _ => {}
        }
        Ok(())
    }
}

/// Parses a record with the `mcap` crate.
fn parse(opcode: u8, body: &[u8]) -> Result<Record<'_>> {
    mcap::parse_record(opcode, body)
        .map_err(|e| anyhow!("a corrupt record (opcode {opcode:#04x}): {e}"))
}

/// The opcode and length of the record at `at`; `None` at the end of the file. The record
/// must fit in the file.
fn record_header(part: &Part, at: u64) -> Result<Option<(u8, u64)>> {
    if at >= part.len {
        return Ok(None);
    }
    let mut head = [0u8; 9];
    part.bytes
        .read_exact_at(&mut head, at)
        .map_err(|_| anyhow!("a record header cut off at byte {at} (truncated?)"))?;
    let len = u64::from_le_bytes(head[1..].try_into().expect("8 bytes"));
    if len > part.len - at - 9 {
        bail!(
            "the record at byte {at} claims {len} bytes, the file has {} left (truncated?)",
            part.len - at - 9
        );
    }
    Ok(Some((head[0], len)))
}

/// The record at `at`: opcode and body, at most [`MAX_RECORD_BYTES`].
fn read_record(part: &Part, at: u64) -> Result<Option<(u8, Vec<u8>)>> {
    let Some((opcode, len)) = record_header(part, at)? else {
        return Ok(None);
    };
    if len > MAX_RECORD_BYTES {
        bail!(
            "the record at byte {at} claims {len} bytes, more than the {MAX_RECORD_BYTES} accepted"
        );
    }
    let mut body = vec![0u8; len as usize];
    part.bytes.read_exact_at(&mut body, at + 9)?;
    Ok(Some((opcode, body)))
}

/// The record at `offset` of a chunk's records: opcode, body and the next record's offset;
/// `None` at the end.
fn inner_record(records: &[u8], offset: usize) -> Result<Option<(u8, &[u8], usize)>> {
    if offset >= records.len() {
        return Ok(None);
    }
    let head = records
        .get(offset..offset + 9)
        .ok_or_else(|| anyhow!("a record header cut off at byte {offset} of a chunk"))?;
    let len = u64::from_le_bytes(head[1..].try_into().expect("8 bytes"));
    let left = (records.len() - offset - 9) as u64;
    if len > left {
        bail!(
            "the record at byte {offset} of a chunk claims {len} bytes, the chunk has {left} left"
        );
    }
    let end = offset + 9 + len as usize;
    Ok(Some((head[0], &records[offset + 9..end], end)))
}

/// A chunk's records, decompressed (at most [`MAX_RECORD_BYTES`]).
fn decompress<'a>(header: &ChunkHeader, data: &'a [u8]) -> Result<Cow<'a, [u8]>> {
    let size = header.uncompressed_size;
    if size > MAX_RECORD_BYTES {
        bail!(
            "a chunk claims {size} bytes uncompressed, more than the {MAX_RECORD_BYTES} accepted"
        );
    }
    let out = match header.compression.as_str() {
        "" => Cow::Borrowed(data),
        "zstd" => Cow::Owned(
            zstd::bulk::decompress(data, size as usize)
                .map_err(|e| anyhow!("a zstd chunk does not decompress: {e}"))?,
        ),
        "lz4" => {
            use std::io::Read;
            let mut out = Vec::with_capacity(size as usize);
            lz4::Decoder::new(data)
                .and_then(|d| d.take(size).read_to_end(&mut out))
                .map_err(|e| anyhow!("an lz4 chunk does not decompress: {e}"))?;
            Cow::Owned(out)
        }
        other => bail!("a chunk compressed with {other:?} (zstd, lz4 or none are read)"),
    };
    if out.len() as u64 != size {
        bail!(
            "a chunk holds {} bytes uncompressed, its header says {size}",
            out.len()
        );
    }
    Ok(out)
}
