"""The C37.118.2 check the frame tests share (tests/estimation): written once from the
standard, not from the code under test.

Importable from any test module (``tests/`` is on ``sys.path``, as ``model_rows``)."""


def crc_ccitt(data: bytes) -> int:
    """CRC-CCITT of C37.118.2-2011 Annex B: polynomial x^16 + x^12 + x^5 + 1, initial
    0xFFFF, no reflection, no final XOR."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc
