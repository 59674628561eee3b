//! The records of an MCAP file walked in blocks from disk, every record's length bounded
//! before anything is allocated for it: the messages in file order ([`each_message`]) and the
//! metadata through the summary section ([`Summary`]). Memory does not grow with the file; the
//! readers of [`super::mcap_log`] and [`super::mcap_stream`] stand on it.

use super::IoError;
use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};
use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

/// Bytes read from the file at a time.
const BLOCK: usize = 1 << 20;

/// The longest record an MCAP file of `file_bytes` bytes may hold, checked before anything is
/// allocated for one: 100 times the file (a compressed chunk's records), at least 64 MiB. A
/// corrupt length inside a chunk would otherwise make a reader reserve exabytes and abort.
pub(crate) fn record_length_limit(file_bytes: u64) -> usize {
    usize::try_from(file_bytes)
        .unwrap_or(usize::MAX)
        .saturating_mul(100)
        .max(64 << 20)
}

/// What a walk does after a message.
pub(crate) enum Flow {
    Go,
    Stop,
}

/// One message met by [`each_message`]: its channel's topic and schema name (empty without a
/// schema), its log time (ns), sequence number and undecoded data.
pub(crate) struct MessageRef<'a> {
    pub topic: &'a str,
    pub schema: &'a str,
    pub log_time: u64,
    pub sequence: u32,
    pub data: &'a [u8],
}

/// Why a walk over the messages ended early: the file (named), or what the caller said of a
/// message.
pub(crate) enum Walked {
    Io(IoError),
    Message(String),
}

impl Walked {
    /// The error of reading `path`: the file's own, or what was said of a message, naming it.
    pub(crate) fn into_io(self, path: &Path) -> IoError {
        match self {
            Walked::Io(e) => e,
            Walked::Message(m) => IoError::invalid(path, m),
        }
    }
}

/// Reads every record of `path` in blocks of at most [`BLOCK`] bytes, chunks decompressed one
/// at a time and every record's length bounded before anything is allocated for it, passing
/// each message in file order to `each` until it says stop: memory independent of the file's
/// length beyond what `each` keeps.
pub(crate) fn each_message(
    path: &Path,
    each: &mut dyn FnMut(MessageRef) -> Result<Flow, String>,
) -> Result<(), Walked> {
    let fs_error = |source| {
        Walked::Io(IoError::Fs {
            path: path.to_path_buf(),
            source,
        })
    };
    let mut file = std::fs::File::open(path).map_err(fs_error)?;
    let size = file.metadata().map_err(fs_error)?.len();
    let bad = |m: String| Walked::Io(IoError::invalid(path, m));
    let options =
        LinearReaderOptions::default().with_record_length_limit(record_length_limit(size));
    let mut reader = LinearReader::new_with_options(options);
    let mut channels = Channels::default();
    let mut i = 0usize;
    while let Some(event) = reader.next_event() {
        let event = event.map_err(|e| bad(format!("not a readable MCAP file: {e}")))?;
        let (opcode, data) = match event {
            LinearReadEvent::ReadRequest(wanted) => {
                let buf = reader.insert(wanted.min(BLOCK));
                let got = file.read(buf).map_err(fs_error)?;
                reader.notify_read(got);
                continue;
            }
            LinearReadEvent::Record { opcode, data } => (opcode, data),
        };
        let record =
            mcap::parse_record(opcode, data).map_err(|e| bad(format!("record {i}: {e}")))?;
        if let Flow::Stop = channels.visit(record, i, each)? {
            return Ok(());
        }
        i += 1;
    }
    Ok(())
}

/// The schema and channel records met so far: each channel's topic and schema name.
#[derive(Default)]
struct Channels {
    schemas: HashMap<u16, String>,
    channels: HashMap<u16, (String, String)>,
}

impl Channels {
    /// Notes record `i` if it declares a schema or a channel; hands a message to `each` with
    /// its channel's topic and schema (an error for a channel no record declared).
    fn visit(
        &mut self,
        record: Record,
        i: usize,
        each: &mut dyn FnMut(MessageRef) -> Result<Flow, String>,
    ) -> Result<Flow, Walked> {
        match record {
            Record::Schema { header, .. } => {
                self.schemas.insert(header.id, header.name);
            }
            Record::Channel(c) => {
                let schema = self.schemas.get(&c.schema_id).cloned().unwrap_or_default();
                self.channels.insert(c.id, (c.topic, schema));
            }
            Record::Message { header, data } => {
                let Some((topic, schema)) = self.channels.get(&header.channel_id) else {
                    return Err(Walked::Message(format!(
                        "record {i}: a message on channel {}, which no channel record declares",
                        header.channel_id
                    )));
                };
                let message = MessageRef {
                    topic,
                    schema,
                    log_time: header.log_time,
                    sequence: header.sequence,
                    data: &data,
                };
                return each(message).map_err(Walked::Message);
            }
            _ => {}
        }
        Ok(Flow::Go)
    }
}

/// Every metadata record of the MCAP file `path`, by name, found through its summary section;
/// none when the summary cannot be read (a file cut short, or written without one).
pub(crate) fn all_metadata(path: &Path) -> Result<MetadataByName, IoError> {
    let mut out = MetadataByName::new();
    let Ok(Some(mut summary)) = Summary::open(path) else {
        return Ok(out);
    };
    for index in std::mem::take(&mut summary.indexes) {
        let record = summary.record(&index)?;
        out.insert(index.name, record);
    }
    Ok(out)
}

/// Metadata records by name: each a key-value map.
pub(crate) type MetadataByName =
    std::collections::BTreeMap<String, std::collections::BTreeMap<String, String>>;

/// An MCAP file's summary section, open for its metadata records.
pub(crate) struct Summary<'a> {
    path: &'a Path,
    file: std::fs::File,
    size: u64,
    /// The longest record read (bytes): the summary's records are not compressed, so none is
    /// longer than the file.
    limit: usize,
    pub(crate) indexes: Vec<mcap::records::MetadataIndex>,
}

impl<'a> Summary<'a> {
    /// The summary of `path` (read from the end of the file), `None` without one.
    pub(crate) fn open(path: &'a Path) -> Result<Option<Self>, IoError> {
        use mcap::sans_io::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};
        use std::io::Seek;
        let fs_error = |source| IoError::Fs {
            path: path.to_path_buf(),
            source,
        };
        let bad = |m: String| IoError::invalid(path, m);
        let mut file = std::fs::File::open(path).map_err(fs_error)?;
        let size = file.metadata().map_err(fs_error)?.len();
        let limit = usize::try_from(size).unwrap_or(usize::MAX).max(1 << 20);
        let mut reader = SummaryReader::new_with_options(
            SummaryReaderOptions::default()
                .with_file_size(size)
                .with_record_length_limit(limit),
        );
        while let Some(event) = reader.next_event() {
            match event.map_err(|e| bad(format!("not a readable MCAP file: {e}")))? {
                SummaryReadEvent::ReadRequest(wanted) => {
                    let got = file.read(reader.insert(wanted)).map_err(fs_error)?;
                    reader.notify_read(got);
                }
                SummaryReadEvent::SeekRequest(to) => {
                    reader.notify_seeked(file.seek(to).map_err(fs_error)?);
                }
            }
        }
        Ok(reader.finish().map(|summary| Summary {
            path,
            file,
            size,
            limit,
            indexes: summary.metadata_indexes,
        }))
    }

    /// The metadata record `index` points at (its key-value map), or an error naming it.
    pub(crate) fn record(
        &mut self,
        index: &mcap::records::MetadataIndex,
    ) -> Result<std::collections::BTreeMap<String, String>, IoError> {
        use std::io::Seek;
        let (path, name) = (self.path, &index.name);
        let bad = |m: String| IoError::invalid(path, m);
        let length = usize::try_from(index.length)
            .ok()
            .filter(|&l| {
                (9..=self.limit).contains(&l)
                    && index.offset.saturating_add(index.length) <= self.size
            })
            .ok_or_else(|| {
                bad(format!(
                    "metadata '{name}': its index points outside the file"
                ))
            })?;
        let mut record = vec![0; length];
        self.file
            .seek(std::io::SeekFrom::Start(index.offset))
            .and_then(|_| self.file.read_exact(&mut record))
            .map_err(|source| IoError::Fs {
                path: path.to_path_buf(),
                source,
            })?;
        match mcap::parse_record(record[0], &record[9..]) {
            Ok(Record::Metadata(m)) => Ok(m.metadata),
            Ok(_) => Err(bad(format!(
                "metadata '{name}': its index points at another record"
            ))),
            Err(e) => Err(bad(format!("metadata '{name}': {e}"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// A zstd-chunked MCAP with two schemas, a channel without one, messages interleaved over
    /// three channels across several chunks, and two metadata records.
    fn write_log(path: &Path) {
        let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
        let mut w = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .chunk_size(Some(4096))
            .create(file)
            .unwrap();
        let a = w.add_schema("pkg/msg/A", "ros2msg", b"float64 x").unwrap();
        let b = w.add_schema("pkg/msg/B", "ros2msg", b"string s").unwrap();
        let none = BTreeMap::new();
        let channels = [
            w.add_channel(a, "/a", "cdr", &none).unwrap(),
            w.add_channel(b, "/b", "cdr", &none).unwrap(),
            w.add_channel(0, "/raw", "", &none).unwrap(),
        ];
        for k in 0..3000u32 {
            let channel_id = channels[(k % 3) as usize];
            let header = mcap::records::MessageHeader {
                channel_id,
                sequence: k,
                log_time: 1_000 + 7 * u64::from(k),
                publish_time: 0,
            };
            let data: Vec<u8> = (0..(k % 40)).map(|i| (i * 31 + k) as u8).collect();
            w.write_to_known_channel(&header, &data).unwrap();
        }
        for (name, value) in [("first", "1"), ("second", "two")] {
            let metadata = [("key".to_string(), value.to_string())].into();
            w.write_metadata(&mcap::records::Metadata {
                name: name.into(),
                metadata,
            })
            .unwrap();
        }
        w.finish().unwrap();
    }

    /// The walk meets every message the mcap crate's whole-file reader does, in the same
    /// order, with the same channel, times and bytes; and the metadata its summary indexes.
    #[test]
    fn the_block_walk_meets_what_the_whole_file_reader_does() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("log.mcap");
        write_log(&path);
        let bytes = std::fs::read(&path).unwrap();
        assert!(
            bytes.len() > 2 * 4096,
            "several chunks: {} bytes",
            bytes.len()
        );
        let whole: Vec<(String, String, u64, u32, Vec<u8>)> = mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(|m| {
                let m = m.unwrap();
                let schema = m.channel.schema.as_ref().map_or("", |s| s.name.as_str());
                let data = m.data.to_vec();
                (
                    m.channel.topic.clone(),
                    schema.into(),
                    m.log_time,
                    m.sequence,
                    data,
                )
            })
            .collect();
        let mut walked = vec![];
        each_message(&path, &mut |m| {
            let data = m.data.to_vec();
            walked.push((
                m.topic.into(),
                m.schema.into(),
                m.log_time,
                m.sequence,
                data,
            ));
            Ok(Flow::Go)
        })
        .unwrap_or_else(|_| panic!("the walk failed"));
        assert_eq!(whole.len(), 3000);
        assert_eq!(walked, whole);
        let metadata = all_metadata(&path).unwrap();
        assert_eq!(metadata.len(), 2);
        assert_eq!(metadata["second"]["key"], "two");
        // Stopping early stops: the first hundred messages only.
        let mut seen = 0;
        each_message(&path, &mut |_| {
            seen += 1;
            Ok(if seen == 100 { Flow::Stop } else { Flow::Go })
        })
        .unwrap_or_else(|_| panic!("the walk failed"));
        assert_eq!(seen, 100);
    }
}
