"""Signing and verifying motormix's LCM messages from Python.

The same trailer as motormix/signing.hpp (the C++ library): 27 bytes after
the LCM payload, which generated decoders never read:
"MMS1", a link id (1 byte), a timestamp (6 bytes, little-endian, 10 us
units since 2015-01-01 UTC), and HMAC-SHA256 over the channel name, a zero
byte, the payload and those 11 bytes, truncated to 16 bytes.

    key = load_key("/etc/motormix/bus.key")
    signer = Signer(key, link_id=20)
    lc.publish("SETPOINT", signer.sign("SETPOINT", msg.encode()))

Only the standard library (hmac, hashlib, os). The key is 64 hexadecimal
digits in a file only its owner can read (`motormix keygen`).
"""

import hashlib
import hmac
import os
import stat
import time

MAGIC = b"MMS1"
HEADER_BYTES = 11
TAG_BYTES = 16
TRAILER_BYTES = HEADER_BYTES + TAG_BYTES
_EPOCH_2015_US = 1420070400 * 1000000
_TIMESTAMP_MAX = (1 << 48) - 1


class KeyError_(Exception):
    """A key file that cannot be used (the message never holds the key)."""


def load_key(path):
    """The 32-byte key in path; refuses a file group or others can read."""
    st = os.stat(path)
    if st.st_mode & 0o077:
        raise KeyError_(f"the key file {path} can be read by group or others; refused (chmod 600 {path})")
    with open(path, "rb") as f:
        text = f.read(130).strip()
    try:
        key = bytes.fromhex(text.decode("ascii"))
    except (UnicodeDecodeError, ValueError):
        key = b""
    if len(key) != 32:
        raise KeyError_(f"the key file {path} does not hold a key (64 hexadecimal digits)")
    return key


def timestamp_of(unix_us):
    """Unix microseconds to the trailer's 10 us units since 2015."""
    if unix_us <= _EPOCH_2015_US:
        return 1
    return min((unix_us - _EPOCH_2015_US) // 10, _TIMESTAMP_MAX)


def _tag(key, channel, payload, header):
    mac = hmac.new(key, channel.encode() + b"\0" + payload + header, hashlib.sha256)
    return mac.digest()[:TAG_BYTES]


class Signer:
    """Appends a trailer; timestamps never repeat, even if the clock stalls."""

    def __init__(self, key, link_id):
        if not 0 <= link_id <= 255:
            raise ValueError("link_id is one byte: 0..255")
        self._key = key
        self._link = link_id
        self._last = 0

    def sign(self, channel, payload, now_unix_us=None):
        if now_unix_us is None:
            now_unix_us = time.time_ns() // 1000
        ts = min(max(timestamp_of(now_unix_us), self._last + 1), _TIMESTAMP_MAX)
        self._last = ts
        header = MAGIC + bytes([self._link]) + ts.to_bytes(6, "little")
        return payload + header + _tag(self._key, channel, payload, header)


class Verifier:
    """Per link and channel, the newest timestamp taken; see motormix/signing.hpp."""

    def __init__(self, key, max_skew_s=60.0):
        self._key = key
        self._skew = int(max_skew_s * 1e5)
        self._last = {}

    def verify(self, channel, data, now_unix_us=None):
        """(verdict, payload): 'signed', 'unsigned', 'bad signature', 'replayed', 'stale timestamp'."""
        if len(data) < TRAILER_BYTES or data[-TRAILER_BYTES:-TRAILER_BYTES + 4] != MAGIC:
            return "unsigned", data
        payload, trailer = data[:-TRAILER_BYTES], data[-TRAILER_BYTES:]
        header = trailer[:HEADER_BYTES]
        if not hmac.compare_digest(_tag(self._key, channel, payload, header), trailer[HEADER_BYTES:]):
            return "bad signature", payload
        if now_unix_us is None:
            now_unix_us = time.time_ns() // 1000
        link, ts = trailer[4], int.from_bytes(trailer[5:11], "little")
        last = self._last.get((link, channel), 0)
        if last == 0:
            if abs(ts - timestamp_of(now_unix_us)) > self._skew:
                return "stale timestamp", payload
        elif ts <= last:
            return "replayed", payload
        self._last[(link, channel)] = ts
        return "signed", payload
