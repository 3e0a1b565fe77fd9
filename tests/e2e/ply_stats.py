#!/usr/bin/env python3
"""A PLY's point count and bounding box, read independently of sweepmap (other_tools.sh).

  ply_stats.py count FILE.ply           prints the vertex count
  ply_stats.py compare FILE.ply OUT.asc checks that OUT.asc (x y z [...] per line, as another
                                        program saved what it loaded) holds as many points
                                        with the same bounding box (to 1e-5 m); exit 1 if not
Reads binary_little_endian and ascii PLYs with any float/double/int vertex properties.
"""
import struct
import sys

TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
         "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
         "float": "f", "float32": "f", "double": "d", "float64": "d"}


def read_header(data, path):
    end = data.find(b"end_header\n")
    if not data.startswith(b"ply\n") or end < 0:
        sys.exit(f"{path}: not a PLY (no 'ply' magic or no end_header)")
    fmt, count, props, element = None, None, [], None
    for line in data[:end].decode("ascii").splitlines():
        words = line.split()
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            element = words[1]
            if element == "vertex":
                count = int(words[2])
        elif words[0] == "property" and element == "vertex":
            if words[1] == "list" or words[1] not in TYPES:
                sys.exit(f"{path}: vertex property '{line}' not read by this checker")
            props.append((words[2], TYPES[words[1]]))
    return fmt, count, props, end + len(b"end_header\n")


def ply_points(path):
    data = open(path, "rb").read()
    fmt, count, props, start = read_header(data, path)
    names = [n for n, _ in props]
    ix, iy, iz = names.index("x"), names.index("y"), names.index("z")
    if fmt == "ascii":
        rows = data[start:].decode("ascii").split("\n")[:count]
        return [tuple(float(r.split()[i]) for i in (ix, iy, iz)) for r in rows]
    if fmt != "binary_little_endian":
        sys.exit(f"{path}: format {fmt} not read by this checker")
    vertex = struct.Struct("<" + "".join(t for _, t in props))
    return [(v[ix], v[iy], v[iz]) for v in vertex.iter_unpack(data[start:start + count * vertex.size])]


def asc_points(path):
    points = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            words = line.replace(",", " ").split()
            if not words or words[0].startswith("/"):
                continue
            try:
                points.append(tuple(float(w) for w in words[:3]))
            except ValueError:
                sys.exit(f"{path}:{n}: not 'x y z ...': {line.strip()}")
    return points


def bounds(points):
    return [min(p[i] for p in points) for i in range(3)] + [max(p[i] for p in points) for i in range(3)]


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "count":
        print(read_header(open(sys.argv[2], "rb").read(), sys.argv[2])[1])
        return 0
    if len(sys.argv) != 4 or sys.argv[1] != "compare":
        sys.exit(__doc__)
    ours, theirs = ply_points(sys.argv[2]), asc_points(sys.argv[3])
    ok = len(ours) == len(theirs)
    print(f"{sys.argv[2]}: {len(ours)} points; {sys.argv[3]}: {len(theirs)} points")
    if ours and theirs:
        b_ours, b_theirs = bounds(ours), bounds(theirs)
        worst = max(abs(a - b) for a, b in zip(b_ours, b_theirs))
        print("  bounds ours   " + " ".join(f"{v:.5f}" for v in b_ours))
        print("  bounds theirs " + " ".join(f"{v:.5f}" for v in b_theirs) + f"  (worst {worst:.2e} m)")
        ok = ok and worst <= 1e-5
    return 0 if ok and ours else 1


if __name__ == "__main__":
    sys.exit(main())
