#!/usr/bin/env python3
"""Rewrites an Android 15 (API 35) framework resource table so that an older aapt2 can link against it.

    arsc-compat.py ANDROID_ALL_JAR OUT_JAR

Android 15's resources.arsc stores most entries in the compact form (FLAG_COMPACT: key, type and value in 8 bytes)
and their offsets in 16 bits (FLAG_OFFSET16), which aapt2 learned in Android 15; Debian's aapt2 (Android 10) reads
neither and finds no framework resource at all. This writes the same table in the encoding every aapt2 reads: each
compact entry as a full ResTable_entry and Res_value, 32-bit offsets. Resource ids, names and values stay as they are,
so an app linked against the result is linked against API 35. OUT_JAR holds only the rewritten resources.arsc, which
is all `aapt2 link -I` reads.
"""
import struct
import sys
import zipfile

RES_TABLE_TYPE = 0x0002
RES_TABLE_PACKAGE_TYPE = 0x0200
RES_TABLE_TYPE_TYPE = 0x0201
NO_ENTRY = 0xFFFFFFFF
FLAG_SPARSE = 0x01
FLAG_OFFSET16 = 0x02
FLAG_COMPLEX = 0x0001
FLAG_COMPACT = 0x0008


def chunks(data, start, end):
    while start < end:
        kind, header, size = struct.unpack_from('<HHI', data, start)
        yield start, kind, header, size
        start += size


def entry_bytes(data, at):
    """The entry at `at` in its full encoding."""
    size, flags = struct.unpack_from('<HH', data, at)
    if flags & FLAG_COMPACT:
        key, value = struct.unpack_from('<HI', data, at)[0], struct.unpack_from('<I', data, at + 4)[0]
        data_type = flags >> 8
        plain = flags & 0x00FF & ~FLAG_COMPACT
        return struct.pack('<HHI', 8, plain, key) + struct.pack('<HBBI', 8, 0, data_type, value)
    if flags & FLAG_COMPLEX:
        count = struct.unpack_from('<I', data, at + 12)[0]
        return data[at:at + size + count * 12]
    value_size = struct.unpack_from('<H', data, at + size)[0]
    return data[at:at + size + value_size]


def rewrite_type(data, start, header, size):
    flags = data[start + 9]
    count, entries_start = struct.unpack_from('<II', data, start + 12)
    table = start + header
    if flags & FLAG_SPARSE:
        indexed = [struct.unpack_from('<HH', data, table + 4 * i) for i in range(count)]
        entries = [(index, entry_bytes(data, start + entries_start + offset * 4)) for index, offset in indexed]
    else:
        if flags & FLAG_OFFSET16:
            offsets = [o * 4 if o != 0xFFFF else NO_ENTRY for o in struct.unpack_from('<%dH' % count, data, table)]
        else:
            offsets = list(struct.unpack_from('<%dI' % count, data, table))
        entries = [(i, entry_bytes(data, start + entries_start + o)) for i, o in enumerate(offsets) if o != NO_ENTRY]
    body, offset_of = bytearray(), {}
    for index, entry in entries:
        offset_of[index] = len(body)
        body += entry
    if flags & FLAG_SPARSE:
        if len(body) // 4 > 0xFFFF:
            sys.exit('arsc-compat: a sparse type grew past 16-bit offsets')
        offsets = b''.join(struct.pack('<HH', i, offset_of[i] // 4) for i, _ in entries)
    else:
        offsets = b''.join(struct.pack('<I', offset_of.get(i, NO_ENTRY)) for i in range(count))
    new_header = bytearray(data[start:start + header])
    new_start = header + len(offsets)
    struct.pack_into('<I', new_header, 4, new_start + len(body))
    new_header[9] = flags & ~FLAG_OFFSET16
    struct.pack_into('<I', new_header, 16, new_start)
    return bytes(new_header) + offsets + bytes(body)


def rewrite(data):
    kind, header, _ = struct.unpack_from('<HHI', data, 0)
    assert kind == RES_TABLE_TYPE, 'not a resource table'
    out = bytearray(data[:header])
    for start, kind, sub_header, size in chunks(data, header, len(data)):
        if kind != RES_TABLE_PACKAGE_TYPE:
            out += data[start:start + size]
            continue
        package = bytearray(data[start:start + sub_header])
        for inner, inner_kind, inner_header, inner_size in chunks(data, start + sub_header, start + size):
            if inner_kind == RES_TABLE_TYPE_TYPE:
                package += rewrite_type(data, inner, inner_header, inner_size)
            else:
                package += data[inner:inner + inner_size]
        struct.pack_into('<I', package, 4, len(package))
        out += package
    struct.pack_into('<I', out, 4, len(out))
    return bytes(out)


def main():
    source, target = sys.argv[1:3]
    with zipfile.ZipFile(source) as jar:
        table = jar.read('resources.arsc')
    with zipfile.ZipFile(target, 'w', zipfile.ZIP_STORED) as out:
        out.writestr('resources.arsc', rewrite(table))


if __name__ == '__main__':
    main()
