"""Writes a weight file whose tensors do not fit its config: the tensors of
one weight file under the config of another (no torch needed).

  python3 tests/cli/make_bad_weights.py TENSORS.safetensors CONFIG_FROM.safetensors OUT.safetensors
"""

import json
import struct
import sys


def read(path):
    with open(path, "rb") as f:
        data = f.read()
    (n,) = struct.unpack("<Q", data[:8])
    return json.loads(data[8:8 + n]), data[8 + n:]


def main(tensors_path, config_path, out_path):
    header, body = read(tensors_path)
    header["__metadata__"]["vtloc.config"] = read(config_path)[0]["__metadata__"]["vtloc.config"]
    text = json.dumps(header).encode()
    text += b" " * (-len(text) % 8)
    with open(out_path, "wb") as f:
        f.write(struct.pack("<Q", len(text)) + text + body)


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
