//! ROS 2 bags (rosbag2 directories): `metadata.yaml` read with a YAML parser, and the two
//! storage formats ROS 2 writes: MCAP (the newer default) and SQLite 3 (the default before
//! it, still common), whose `messages` table holds the same CDR messages
//! (read with rusqlite, SQLite itself compiled in).

use super::mcap_log::Reader;
use super::IoError;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// How a bag stores its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// MCAP files.
    Mcap,
    /// SQLite 3 databases (`.db3`).
    Sqlite3,
}

/// `metadata.yaml`: the keys physid reads (others are ignored).
#[derive(Deserialize, Debug)]
struct Metadata {
    rosbag2_bagfile_information: Information,
}

#[derive(Deserialize, Debug)]
struct Information {
    storage_identifier: Option<String>,
    #[serde(default)]
    relative_file_paths: Vec<String>,
    #[serde(default)]
    topics_with_message_count: Vec<TopicCount>,
}

/// One entry of `topics_with_message_count`.
#[derive(Deserialize, Debug)]
struct TopicCount {
    topic_metadata: TopicMetadata,
    #[serde(default)]
    message_count: u64,
}

#[derive(Deserialize, Debug)]
struct TopicMetadata {
    name: String,
    #[serde(rename = "type")]
    kind: String,
}

/// The bag's `metadata.yaml`, parsed; errors name the file.
fn information(dir: &Path) -> Result<(PathBuf, Information), IoError> {
    let meta_path = dir.join("metadata.yaml");
    if !meta_path.is_file() {
        return Err(IoError::invalid(
            dir,
            "is a directory without metadata.yaml (give an MCAP file or a rosbag2 directory)",
        ));
    }
    let text = super::read_to_string(&meta_path)?;
    let meta: Metadata = serde_yaml_ng::from_str(&text)
        .map_err(|e| IoError::invalid(&meta_path, format!("not a rosbag2 metadata file: {e}")))?;
    Ok((meta_path, meta.rosbag2_bagfile_information))
}

/// The storage files of a rosbag2 directory, in the order its `metadata.yaml` lists them
/// (`relative_file_paths`), and how they store messages. Errors name the directory or the
/// metadata file and the key at fault.
pub fn files(dir: &Path) -> Result<(Vec<PathBuf>, Storage), IoError> {
    open(dir).map(|bag| (bag.files, bag.storage))
}

/// A rosbag2 directory as its `metadata.yaml` describes it, read once: its storage files and
/// how they store messages ([`files`]), and the topics it lists.
pub(crate) struct Bag {
    pub files: Vec<PathBuf>,
    pub storage: Storage,
    meta_path: PathBuf,
    listed: Vec<TopicCount>,
}

impl Bag {
    /// Checks the topics the bag's files hold (`stored`: name → message type, of those with
    /// messages) against those its `metadata.yaml` lists with messages: a topic listed with
    /// another type, or listed with messages none of the files has, means the metadata belongs
    /// to another recording (or the files to another bag), and is refused naming both.
    pub fn check_listed_topics(
        &self,
        stored: &std::collections::BTreeMap<String, String>,
    ) -> Result<(), IoError> {
        for listed in &self.listed {
            let TopicMetadata { name, kind } = &listed.topic_metadata;
            let problem = match stored.get(name) {
                Some(had) if had != kind => format!("lists {name} as {kind}, but the bag's files store it as {had}"),
                None if listed.message_count > 0 => format!(
                    "lists {name} ({kind}) with {} messages, but none of the bag's files has a message on it",
                    listed.message_count
                ),
                _ => continue,
            };
            return Err(IoError::invalid(
                &self.meta_path,
                format!("{problem}: the metadata and the storage files are of different recordings (`ros2 bag reindex` rewrites metadata.yaml from the files)"),
            ));
        }
        Ok(())
    }
}

/// The bag in `dir`, its `metadata.yaml` checked: a storage physid reads, files listed once
/// each and present.
pub(crate) fn open(dir: &Path) -> Result<Bag, IoError> {
    let (meta_path, info) = information(dir)?;
    let bad = |m: String| IoError::invalid(&meta_path, m);
    let storage = match info.storage_identifier.as_deref() {
        Some("mcap") => Storage::Mcap,
        Some("sqlite3") => Storage::Sqlite3,
        // Before storage_identifier was written, the extension tells.
        None if info.relative_file_paths.iter().all(|f| f.ends_with(".db3")) => Storage::Sqlite3,
        None => Storage::Mcap,
        Some(other) => {
            return Err(bad(format!(
                "storage_identifier is '{other}'; physid reads bags stored as mcap or sqlite3"
            )))
        }
    };
    if info.relative_file_paths.is_empty() {
        return Err(bad("lists no relative_file_paths".into()));
    }
    let listed = &info.relative_file_paths;
    if let Some((j, i)) = super::first_repeat(listed, |_| true) {
        return Err(bad(format!(
            "lists {} twice in relative_file_paths (entries {} and {}): each file of a recording is read once",
            listed[i],
            j + 1,
            i + 1
        )));
    }
    let files: Vec<PathBuf> = info
        .relative_file_paths
        .iter()
        .map(|f| dir.join(f))
        .collect();
    if let Some(missing) = files.iter().find(|f| !f.is_file()) {
        return Err(bad(format!(
            "lists {}, which does not exist",
            missing.display()
        )));
    }
    Ok(Bag {
        files,
        storage,
        meta_path,
        listed: info.topics_with_message_count,
    })
}

/// A database file compressed whole (`ros2 bag record --compression-mode file`: zstd) is
/// refused by name: SQLite would only say it is not a database.
fn check_not_compressed(path: &Path) -> Result<(), IoError> {
    use std::io::Read;
    let mut magic = [0u8; 4];
    let read = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut magic));
    if read.is_ok() && magic == [0x28, 0xb5, 0x2f, 0xfd] {
        return Err(IoError::invalid(
            path,
            "is zstd-compressed (recorded with --compression-mode file): decompress it first (`zstd -d FILE`, or `ros2 bag decompress`), then read the .db3",
        ));
    }
    Ok(())
}

/// Why message `sequence`'s data column (`value`) is not the CDR bytes rosbag2 stores.
fn not_a_blob(value: Option<rusqlite::types::ValueRef>, sequence: u64) -> String {
    use rusqlite::types::ValueRef;
    let got = match value {
        Some(ValueRef::Text(_)) => "text",
        Some(ValueRef::Integer(_)) => "an integer",
        Some(ValueRef::Real(_)) => "a real number",
        Some(ValueRef::Null) => "NULL",
        _ => "not a blob",
    };
    format!("message {sequence}: its data column holds {got}, where rosbag2 stores each message's CDR bytes as a BLOB")
}

/// Feeds every message of a rosbag2 SQLite database to `reader`, in time order.
pub(crate) fn read_sqlite(path: &Path, reader: &mut Reader) -> Result<(), IoError> {
    use rusqlite::{Connection, OpenFlags};
    let bad = |m: String| IoError::invalid(path, m);
    let sql = |e: rusqlite::Error| bad(format!("not a readable rosbag2 database: {e}"));
    check_not_compressed(path)?;
    let db = Connection::open_with_flags(path, OpenFlags::SQLITE_OPEN_READ_ONLY).map_err(sql)?;
    let mut topics = std::collections::HashMap::new();
    {
        let mut stmt = db
            .prepare("SELECT id, name, type FROM topics")
            .map_err(sql)?;
        let rows = stmt
            .query_map([], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                ))
            })
            .map_err(sql)?;
        for row in rows {
            let (id, name, kind) = row.map_err(sql)?;
            topics.insert(id, (name, kind));
        }
    }
    let mut stmt = db
        .prepare("SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id")
        .map_err(sql)?;
    let mut rows = stmt.query([]).map_err(sql)?;
    let mut sequence = 0u64;
    while let Some(row) = rows.next().map_err(sql)? {
        let id: i64 = row.get(0).map_err(sql)?;
        let stamp: i64 = row.get(1).map_err(sql)?;
        let data = row
            .get_ref(2)
            .map_err(sql)?
            .as_blob()
            .map_err(|_| bad(not_a_blob(row.get_ref(2).ok(), sequence)))?;
        let (topic, kind) = topics.get(&id).ok_or_else(|| {
            bad(format!(
                "message {sequence} names topic id {id}, which the topics table lacks"
            ))
        })?;
        let stamp = u64::try_from(stamp).map_err(|_| {
            bad(format!(
                "{topic} message {sequence}: negative timestamp {stamp} ns"
            ))
        })?;
        reader
            .message(topic, kind, data, stamp, sequence)
            .map_err(bad)?;
        sequence += 1;
    }
    Ok(())
}
