#!/usr/bin/env python3
"""Writes docs/protocol/vectors-v5.txt: hub->host frames (hex) and what each must decode to,
by the rules of docs/protocol.md. The expectations are written here by hand from the document,
not taken from any decoder's output. Run from the project's root:
    python3 docs/protocol/make_vectors.py > docs/protocol/vectors-v5.txt
frames.py (postcard + CRC-32C + COBS) is the reproducers' frame builder (../shared/repro/round2)."""
import sys, os
sys.path.insert(0, os.path.dirname(__file__))
from frames import frame, hello, report, varint, zz

P = ((1000, -2000, 3000), (0, 0, 1000000000))
streams = []
def stream(title, *vectors):
    streams.append((title, vectors))

H5 = hello(protocol=5, precision=0, joints=6, status=1, live=(1, 3, 0x1234), probe=7, probes=(7, 2), number=12, date=20261204)
H5_LINE = "hello protocol=5 precision=0 joints=6 status=0x0001 live=1/3/0x00001234 probe=7 probes=7,2 number=12 date=20261204"
PT = "1000,-2000,3000/0,0,1000000000"

stream("a protocol-5 hub: Hello (calibration number 12 of 2026-12-04), then reports with and without U95 and coordinates",
    (frame(H5), H5_LINE),
    (frame(report(0, 10, 1, P, u95=4000, probe=7)), f"report seq=0 time_us=10 status=0x0001 point={PT}/4000 probe=7"),
    (frame(report(1, 20, 1, P, u95=None, probe=2)), f"report seq=1 time_us=20 status=0x0001 point={PT}/none probe=2"),
    (frame(report(2, 30, 0x0005, None, probe=7)), "report seq=2 time_us=30 status=0x0005 point=none probe=7"),
    (frame(report(3, 40, 0x0401, None, probe=7)), "report seq=3 time_us=40 status=0x0401 point=none probe=7"),
    (frame(report(3, 40, 0x0401, None, probe=7)), "repeated seq=3"),
    (frame(report(3, 41, 0x0401, None, probe=7)), "backward expected=4 report seq=3 time_us=41 status=0x0401 point=none probe=7"),
    (frame(report(9, 50, 1, P, u95=1, probe=7)), f"report seq=9 time_us=50 status=0x0001 point={PT}/1 probe=7"),
)
stream("point 2: a step back of one is one behind; 2^31 behind is backward; 2^31 - 1 ahead is a gap",
    (frame(H5), H5_LINE),
    (frame(report(10, 0, 0x0005, None, probe=7)), "report seq=10 time_us=0 status=0x0005 point=none probe=7"),
    (frame(report(9, 0, 0x0005, None, probe=7)), "backward expected=11 report seq=9 time_us=0 status=0x0005 point=none probe=7"),
    (frame(report(10 + 2**31, 0, 0x0005, None, probe=7)), f"backward expected=10 report seq={10 + 2**31} time_us=0 status=0x0005 point=none probe=7"),
    (frame(report((11 + 2**31 + 2**31 - 1) % 2**32, 0, 0x0005, None, probe=7)), f"report seq={(11 + 2**31 + 2**31 - 1) % 2**32} time_us=0 status=0x0005 point=none probe=7"),
)
stream("F5 and point 11: bit 0 means table state 0; states 9-15 are reserved",
    (frame(H5), H5_LINE),
    (frame(report(0, 0, 0x0081, P, u95=5, probe=7)), "inconsistent(status) report seq=0 time_us=0 status=0x0081 point=none probe=7"),
    (frame(report(1, 0, 0x0011, P, probe=7)), "inconsistent(status) report seq=1 time_us=0 status=0x0011 point=none probe=7"),
    (frame(report(2, 0, 0x0090, None, probe=7)), "inconsistent(status) report seq=2 time_us=0 status=0x0090 point=none probe=7"),
    (frame(report(3, 0, 0x0000, None, probe=7)), "inconsistent(status) report seq=3 time_us=0 status=0x0000 point=none probe=7"),
    (frame(report(4, 0, 0x0080, None, probe=7)), "report seq=4 time_us=0 status=0x0080 point=none probe=7"),
    (frame(report(5, 0, 0x0004 | 1, P, probe=7)), "inconsistent(forbidden) report seq=5 time_us=0 status=0x0005 point=none probe=7"),
    (frame(report(6, 0, 0x0001, None, probe=7)), "inconsistent(missing) report seq=6 time_us=0 status=0x0001 point=none probe=7"),
)
stream("F6: a U95 no encoder writes is no message; an unlisted probe, a direction of no unit length",
    (frame(H5), H5_LINE),
    (frame(report(0, 0, 1, P, u95_raw=b'\x02', probe=7)), "refused undecodable"),
    (frame(report(1, 0, 1, P, u95_raw=b'\x01\xff\xff\xff\xff\x7f', probe=7)), "refused undecodable"),
    (frame(report(2, 0, 1, P, probe=9)), "inconsistent(probe) report seq=2 time_us=0 status=0x0001 point=none probe=9"),
    (frame(report(3, 0, 1, ((1, 2, 3), (0, 0, 0)), probe=7)), "inconsistent(direction) report seq=3 time_us=0 status=0x0001 point=none probe=7"),
    (frame(report(4, 0, 1, ((1, 2, 3), (0, 0, 998000000)), probe=7)), "inconsistent(direction) report seq=4 time_us=0 status=0x0001 point=none probe=7"),
    (frame(report(5, 0, 1, ((1, 2, 3), (0, 0, 999000000)), probe=7)), "report seq=5 time_us=0 status=0x0001 point=1,2,3/0,0,999000000/none probe=7"),
    (frame(report(6, 0, 1, P, probe=7)[:-1]), "refused undecodable"),
    (frame(report(6, 0, 1, P, probe=7) + b'\x00'), "refused undecodable"),
    (frame(report(6, 0, 1, P, probe=7), crc_ok=False), "refused crc"),
)
H_NONE = hello(protocol=5, precision=1, joints=0, status=0x0010, live=None, probe=0, probes=())
stream("a hub without a valid table lists no probe and no calibration: its reports name probe 0",
    (frame(H_NONE), "hello protocol=5 precision=1 joints=0 status=0x0010 live=none probe=0 probes= number=0 date=0"),
    (frame(report(0, 0, 0x0010, None, probe=0)), "report seq=0 time_us=0 status=0x0010 point=none probe=0"),
    (frame(report(1, 0, 0x0010, None, probe=1)), "inconsistent(probe) report seq=1 time_us=0 status=0x0010 point=none probe=1"),
)
H_V4 = hello(protocol=4, precision=0, joints=6, status=1, live=(0, 1, 0xabcd), probe=2, probes=(2, 5))
stream("protocol 4: a Hello without the calibration (read as number 0, date 0), reports as protocol 5's; a protocol-5 Hello cut before its date, or a protocol-4 one with them, is no message",
    (frame(H_V4), "hello protocol=4 precision=0 joints=6 status=0x0001 live=0/1/0x0000abcd probe=2 probes=2,5 number=0 date=0"),
    (frame(report(0, 7, 1, P, u95=3, probe=5)), f"report seq=0 time_us=7 status=0x0001 point={PT}/3 probe=5"),
    (frame(report(1, 8, 1, P, u95=3, probe=7)), "inconsistent(probe) report seq=1 time_us=8 status=0x0001 point=none probe=7"),
    (frame(H5[:-4]), "refused undecodable"),
    (frame(H_V4 + varint(12) + varint(20261204)), "refused undecodable"),
)
H3 = hello(protocol=3, precision=0, joints=6, status=1, live=None)
stream("protocols 3 and 2: reports without the probe id (read as probe 0); a protocol-4 report under them is refused",
    (frame(H3), "hello protocol=3 precision=0 joints=6 status=0x0001 live=none probe=0 probes= number=0 date=0"),
    (frame(report(0, 5, 1, P, u95=7, protocol=3)), f"report seq=0 time_us=5 status=0x0001 point={PT}/7 probe=0"),
    (frame(report(1, 5, 1, P, u95=7, probe=0)), "refused undecodable"),
    (frame(hello(protocol=2, precision=0, joints=6, status=1, live=None)), "hello protocol=2 precision=0 joints=6 status=0x0001 live=none probe=0 probes= number=0 date=0"),
    (frame(report(0, 6, 1, P, protocol=2)), f"report seq=0 time_us=6 status=0x0001 point={PT}/none probe=0"),
)
stream("point 4: after a Hello of an unknown protocol, reports are read as protocol 5's, any probe id passing",
    (frame(varint(0) + varint(6) + varint(0) + bytes([6]) + varint(1)), "foreign-hello protocol=6"),
    (frame(report(0, 0, 1, P, probe=3)), f"report seq=0 time_us=0 status=0x0001 point={PT}/none probe=3"),
)
def update(ok, index, *fields):
    """ToHost::Update (2), Result Ok 0 / Err 1, the Accepted or Refusal variant index, fields."""
    return varint(2) + varint(0 if ok else 1) + varint(index) + b"".join(fields)
stream("update answers: every Accepted and every Refusal (0 to 12), by variant index; 13 is no refusal",
    (frame(update(True, 0, bytes([1]))), "update begun slot=1"),
    (frame(update(True, 1, varint(96))), "update chunk next=96"),
    (frame(update(True, 2, bytes([1]), varint(4))), "update committed slot=1 seq=4"),
    (frame(update(True, 3)), "update aborted"),
    (frame(update(False, 0)), "update refused not-begun"),
    (frame(update(False, 1, varint(70000))), "update refused bad-length len=70000"),
    (frame(update(False, 2, varint(48))), "update refused out-of-order expected=48"),
    (frame(update(False, 3, varint(2456))), "update refused past-end len=2456"),
    (frame(update(False, 4, varint(96), varint(2456))), "update refused incomplete received=96 len=2456"),
    (frame(update(False, 5, varint(8))), "update refused table state=8"),
    (frame(update(False, 6)), "update refused not-announced"),
    (frame(update(False, 7, varint(0), bytes([2]))), "update refused layout unaligned region=2"),
    (frame(update(False, 7, varint(1), bytes([3]))), "update refused layout out-of-flash region=3"),
    (frame(update(False, 7, varint(2), bytes([1]))), "update refused layout slot-too-small slot=1"),
    (frame(update(False, 7, varint(3), bytes([0, 2]))), "update refused layout overlap first=0 second=2"),
    (frame(update(False, 7, varint(4))), "update refused layout write-size-too-large"),
    (frame(update(False, 8, varint(2))), "update refused flash other"),
    (frame(update(False, 9)), "update refused sequence-exhausted"),
    (frame(update(False, 10)), "update refused not-supported"),
    (frame(update(False, 11, varint(6), varint(5))), "update refused rollback live=6 offered=5"),
    (frame(update(False, 11, varint(300), varint(0))), "update refused rollback live=300 offered=0"),
    (frame(update(False, 12)), "update refused retired-key"),
    (frame(update(False, 13)), "refused undecodable"),
    (frame(update(False, 11, varint(6))), "refused undecodable"),
    (frame(varint(3) + varint(0) + bytes([7])), "probe mounted id=7"),
    (frame(varint(3) + varint(1) + varint(0)), "probe refused unknown"),
    (frame(varint(3) + varint(1) + varint(1)), "probe refused no-table"),
)
stream("framing: an unknown variant; an empty frame is idle line; 65 bytes before a delimiter overflow",
    (frame(varint(9)), "refused undecodable"),
    ("00", ""),
    ("020100", "refused short"),
    ("05010100", "refused cobs"),
    ("01" * 66 + "00", "refused overflow"),
    ("02", "refused unterminated"),
)

print("# Conformance vectors of the hub's stream, protocol 5 (docs/protocol.md). Generated by")
print("# docs/protocol/make_vectors.py; replayed by wire/tests/conformance.rs (cargo test --workspace).")
print("#")
print("# A block (blank-line separated) is one stream, read from its start by one decoder.")
print("# Each line: the bytes (hex, a whole frame with its 0x00 unless the expectation says")
print("# otherwise), one space, then what they must give (empty: nothing). Forms:")
print("#   hello protocol=P precision=N joints=J status=0xSSSS live=SLOT/SEQ/0xCRC|none probe=I probes=I,I number=N date=YYYYMMDD")
print("#                                  (the fields a protocol lacks read as 0 / none / empty)")
print("#   foreign-hello protocol=P      (a Hello of a protocol the decoder does not read)")
print("#   report seq=S time_us=T status=0xSSSS point=X,Y,Z/DX,DY,DZ/U95|none probe=I")
print("#   backward expected=E report ...  (a step back without a Hello; numbering restarts from it)")
print("#   repeated seq=S                  (the report before, byte for byte: not written again)")
print("#   inconsistent(WHY) report ...    (handed out without coordinates; WHY: status, forbidden,")
print("#                                    missing, probe, direction)")
print("#   update begun slot=S | chunk next=N | committed slot=S seq=Q | aborted")
print("#   update refused not-begun | bad-length len=L | out-of-order expected=E | past-end len=L")
print("#     | incomplete received=R len=L | table state=N | not-announced | layout unaligned region=R")
print("#     | layout out-of-flash region=R | layout slot-too-small slot=S | layout overlap first=A second=B")
print("#     | layout write-size-too-large | flash not-aligned|out-of-bounds|other | sequence-exhausted")
print("#     | not-supported | rollback live=L offered=O | retired-key")
print("#   probe mounted id=I | probe refused unknown|no-table")
print("#   refused crc|undecodable|cobs|short|overflow|unterminated")
for title, vectors in streams:
    print()
    print("# " + title)
    for data, want in vectors:
        hexs = data if isinstance(data, str) else data.hex()
        print(f"{hexs} {want}".rstrip())
