// Text from input files as UTF-8: glTF and JSON store only UTF-8, while OBJ and MTL files (and file names) carry
// whatever bytes their exporter wrote, often Latin-1 ("Terraind\xe6k").
#pragma once

#include <string>
#include <string_view>

namespace prt {

// Whether `text` is well-formed UTF-8 (RFC 3629): no stray continuation bytes, no overlong forms, no surrogates
// (U+D800..U+DFFF), nothing past U+10FFFF.
bool isUtf8(std::string_view text);

// `text` itself where it is UTF-8, else `text` read as Latin-1 (ISO 8859-1: each byte the code point of its value),
// each byte 0x80..0xff written as its two UTF-8 bytes. The result is always UTF-8, and the same for the same bytes.
std::string utf8FromLatin1(std::string_view text);

// `bytes` as a message may show them, whatever they are: printable ASCII as itself, every other byte as \xNN
// (two lower-case hex digits), at most `maxBytes` bytes of it. The result is printable ASCII.
std::string printableBytes(std::string_view bytes, size_t maxBytes = 200);

} // namespace prt
