"""python/motormix_signing.py: the known answer the C++ library gives
(test/unit/test_signing.cpp), round trips, every changed byte refused,
replays and far clocks refused, a restarted signer taken, key files."""

import os
import stat
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "python"))
import motormix_signing as s  # noqa: E402

NOW_US = 1764806400 * 1000000
KEY = bytes((1 + 7 * i) & 0xFF for i in range(32))
PAYLOAD = bytes((i * 31 + 5) & 0xFF for i in range(57))


def main():
    signed = s.Signer(KEY, 7).sign("SETPOINT", PAYLOAD, NOW_US)
    assert signed[-s.TRAILER_BYTES:].hex() == "4d4d53310700a0ae825a1f605eecc7ad0c271c0c0df9aa86d6bc27"
    v = s.Verifier(KEY)
    assert v.verify("SETPOINT", signed, NOW_US) == ("signed", PAYLOAD)
    assert v.verify("SETPOINT", signed, NOW_US)[0] == "replayed"
    for i in range(len(signed)):
        for bit in range(8):
            bad = bytearray(signed)
            bad[i] ^= 1 << bit
            verdict = s.Verifier(KEY).verify("SETPOINT", bytes(bad), NOW_US)[0]
            assert verdict in ("bad signature", "unsigned"), (i, bit, verdict)
    assert s.Verifier(KEY).verify("PID", signed, NOW_US)[0] == "bad signature"
    assert s.Verifier(KEY).verify("SETPOINT", PAYLOAD, NOW_US) == ("unsigned", PAYLOAD)
    assert s.Verifier(KEY).verify("SETPOINT", signed, NOW_US + 3600 * 10**6)[0] == "stale timestamp"
    again = s.Signer(KEY, 7).sign("SETPOINT", PAYLOAD, NOW_US + 10**6)  # restarted
    assert v.verify("SETPOINT", again, NOW_US + 10**6)[0] == "signed"
    signer = s.Signer(KEY, 1)
    v2 = s.Verifier(KEY)
    for k in range(20):  # a clock that stands still or goes back
        assert v2.verify("X", signer.sign("X", PAYLOAD, NOW_US - (k % 5) * 1000), NOW_US)[0] == "signed"
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "bus.key")
        with open(path, "w") as f:
            f.write(KEY.hex() + "\n")
        os.chmod(path, 0o644)
        try:
            s.load_key(path)
            raise AssertionError("a key readable by others was taken")
        except s.KeyError_ as e:
            assert "group or others" in str(e) and KEY.hex() not in str(e)
        os.chmod(path, stat.S_IRUSR | stat.S_IWUSR)
        assert s.load_key(path) == KEY
    print("motormix_signing.py: known answer, round trip, tampering, replay, stale, restart, keys: ok")


if __name__ == "__main__":
    main()
