"""Seed inputs of sdk/jvm's Jazzer FuzzTest: every golden frame (variant 0) SLIP-encoded, behind the two
bytes FuzzTest reads first (SLIP decoder frame limit - 1 = 124: the protocol's own limit; chunk size - 1 = 15).
The hand-made seeds beside them (broken streams) are not generated."""

SEED_DIRS = ["sdk/jvm/src/test/resources/org/pocketbot/protocol/FuzzTestInputs/decodersNeverThrow",
             "sdk/jvm/src/test/resources/org/pocketbot/protocol/FuzzTestInputs/decodersNeverThrowBriefly"]
PREFIX = bytes([124, 15])



def emit(model, vectors):
    out = {}
    for v in vectors:
        if not v["name"].endswith("_0"):
            continue
        for d in SEED_DIRS:
            out[f"{d}/{v['name']}"] = PREFIX + bytes.fromhex(v["slip"])
    return out
