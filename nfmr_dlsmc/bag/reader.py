"""
Read any rosbag2 MCAP bag (a bag directory or one ``.mcap`` file), complete or truncated.

Records are read in file order with mcap's stream reader, so a bag whose recorder was
killed (no summary, a cut last chunk) is still read up to its last complete chunk; the
result says how much was lost. Problems raise :class:`BagError` with a one-line message.
"""

from dataclasses import dataclass, field
from pathlib import Path
import struct

from mcap.exceptions import McapError
from mcap.records import Channel, Footer, Message, Schema
from mcap.stream_reader import StreamReader
from nfmr_dlsmc.core.errors import NfmrError
from zstandard import ZstdError

MCAP_MAGIC = b'\x89MCAP0\r\n'
#: The opcode of an MCAP chunk record.
CHUNK_OPCODE = 0x06
#: What reading a cut or corrupted record raises: its length runs past the end (EOFError,
#: struct.error), its fields or compressed chunk do not decode or fail their CRC (McapError,
#: ValueError, KeyError, zstandard's ZstdError). Chunk CRCs are checked, so corrupted bytes
#: end the bag instead of turning into wrong messages.
_CUT_OR_CORRUPT = (McapError, EOFError, ValueError, KeyError, struct.error, ZstdError)


class BagError(NfmrError):
    """A bag that cannot be read as asked: the message says what and where."""


@dataclass
class BagMessage:
    """One recorded message: topic, type name, log time [ns] and the CDR payload."""

    topic: str
    type_name: str
    log_time: int
    publish_time: int
    data: bytes


@dataclass
class BagContents:
    """
    Messages of a bag in file order, with what the reader could tell about it.

    Attributes
    ----------
    path : Path
        The ``.mcap`` file read.
    messages : list of BagMessage
    topics : dict
        Topic -> (type name, channel metadata dict).
    truncated : bool
        The file ended before its footer (e.g. the recorder was killed), or a record could
        not be read and reading stopped there.
    unread_bytes : int
        Bytes after the last complete record that could not be used.
    corrupt_chunks : int
        Chunks skipped because their content failed its CRC or did not decompress; the
        chunks after them were read.
    corrupt_bytes : int
        The size of those chunks [bytes].

    """

    path: Path
    messages: list = field(default_factory=list)
    topics: dict = field(default_factory=dict)
    truncated: bool = False
    unread_bytes: int = 0
    corrupt_chunks: int = 0
    corrupt_bytes: int = 0

    def of(self, topic: str) -> list:
        """Return the messages of one topic, in order."""
        return [m for m in self.messages if m.topic == topic]

    def warning(self) -> str | None:
        """Return a one-line note when the bag was truncated or had corrupt chunks."""
        if not (self.truncated or self.corrupt_chunks):
            return None
        span = (self.messages[-1].log_time - self.messages[0].log_time) * 1e-9 \
            if self.messages else 0.0
        notes = []
        if self.corrupt_chunks:
            notes.append(f'{self.corrupt_chunks} corrupt chunk(s) skipped ('
                         f'{self.corrupt_bytes} bytes: their messages are lost, the chunks '
                         'after them were read)')
        if self.truncated:
            notes.append(f'the last {self.unread_bytes} bytes (an incomplete or unreadable '
                         'record) are lost')
        kind = 'truncated bag (no footer)' if self.truncated else 'damaged bag'
        return (f'{self.path}: {kind}: read {len(self.messages)} messages covering '
                f"{span:.3f} s; {'; '.join(notes)}")


def mcap_file(path) -> Path:
    """Return the ``.mcap`` file of a bag directory, or ``path`` itself if it is a file."""
    path = Path(path)
    if not path.exists():
        raise BagError(f'{path}: no such file or directory')
    if path.is_dir():
        files = sorted(path.glob('*.mcap'))
        if not files:
            raise BagError(f'{path}: no .mcap file in this directory')
        if len(files) > 1:
            raise BagError(f"{path}: several .mcap files ({', '.join(f.name for f in files)}); "
                           'name one')
        return files[0]
    return path


def iter_bag(path, topics=None, contents: BagContents | None = None):
    """
    Yield the messages of a bag in file order without holding them all.

    ``contents`` (optional) is filled as reading goes: its ``topics`` gain each channel
    before that channel's first message, and ``truncated`` / ``unread_bytes`` are set when
    the file ends early.

    Raises
    ------
    BagError
        Missing path or not an MCAP file.

    """
    file = mcap_file(path)
    contents = BagContents(path=file) if contents is None else contents
    contents.path = file
    wanted = None if topics is None else set(topics)
    with file.open('rb') as stream:
        if stream.read(len(MCAP_MAGIC)) != MCAP_MAGIC:
            raise BagError(f'{file}: not an MCAP file (it does not start with the MCAP magic)')
        stream.seek(0)
        size = file.stat().st_size
        schemas, channels = {}, {}
        position = 0
        reader = StreamReader(stream, record_size_limit=1 << 31, validate_crcs=True)
        while True:
            try:
                for record in reader.records:
                    if isinstance(record, Schema):
                        schemas[record.id] = record
                    elif isinstance(record, Channel):
                        schema = schemas.get(record.schema_id)
                        type_name = schema.name if schema else ''
                        channels[record.id] = (record.topic, type_name)
                        contents.topics[record.topic] = (type_name, dict(record.metadata))
                    elif isinstance(record, Message):
                        topic, type_name = channels[record.channel_id]
                        if wanted is None or topic in wanted:
                            yield BagMessage(topic, type_name, record.log_time,
                                             record.publish_time, record.data)
                    elif isinstance(record, Footer):
                        break
                    position = stream.tell()
                else:
                    contents.truncated = True
                break
            except _CUT_OR_CORRUPT:
                # A chunk whose own length is sound is skipped whole and reading goes on
                # after it; anything else ends the bag where it starts.
                end = _chunk_end(stream, position, size)
                if end is None:
                    contents.truncated = True
                    break
                contents.corrupt_chunks += 1
                contents.corrupt_bytes += end - position
                stream.seek(end)
                position = end
                reader = StreamReader(stream, skip_magic=True, record_size_limit=1 << 31,
                                      validate_crcs=True)
        if contents.truncated:
            contents.unread_bytes = max(0, size - position)


def _chunk_end(stream, position: int, size: int) -> int | None:
    """Return where the chunk record at ``position`` ends, or None if it is no chunk."""
    stream.seek(position)
    header = stream.read(1 + 8)  # opcode, then the record's length (uint64, little-endian)
    if len(header) < 9 or header[0] != CHUNK_OPCODE:
        return None
    end = position + len(header) + int.from_bytes(header[1:], 'little')
    return end if end <= size else None


def read_bag(path, topics=None) -> BagContents:
    """
    Read a whole bag; ``topics`` (an iterable of names) keeps only those.

    Raises
    ------
    BagError
        Missing path or not an MCAP file.

    """
    contents = BagContents(path=Path(path))
    contents.messages = list(iter_bag(path, topics, contents))
    return contents
