// UTF-8 validation and the Latin-1 fallback (utf8.h).
#include "utf8.h"

#include <cstdint>

namespace prt {

bool isUtf8(std::string_view text) {
    const auto byte = [&](size_t i) { return uint8_t(text[i]); };
    for (size_t i = 0; i < text.size();) {
        const uint8_t lead = byte(i);
        if (lead < 0x80) {
            ++i;
            continue;
        }
        // The sequence's length, and the range its second byte must lie in (which excludes overlong forms,
        // surrogates and code points past U+10FFFF).
        size_t length = 0;
        uint8_t low = 0x80, high = 0xbf;
        if (lead >= 0xc2 && lead <= 0xdf) length = 2;
        else if (lead == 0xe0) length = 3, low = 0xa0;
        else if (lead == 0xed) length = 3, high = 0x9f;
        else if (lead >= 0xe1 && lead <= 0xef) length = 3;
        else if (lead == 0xf0) length = 4, low = 0x90;
        else if (lead >= 0xf1 && lead <= 0xf3) length = 4;
        else if (lead == 0xf4) length = 4, high = 0x8f;
        else return false; // a continuation byte, 0xc0, 0xc1 or 0xf5..0xff
        if (text.size() - i < length || byte(i + 1) < low || byte(i + 1) > high) return false;
        for (size_t k = 2; k < length; ++k)
            if (byte(i + k) < 0x80 || byte(i + k) > 0xbf) return false;
        i += length;
    }
    return true;
}

std::string utf8FromLatin1(std::string_view text) {
    if (isUtf8(text)) return std::string(text);
    std::string out;
    out.reserve(text.size() * 2);
    for (char c : text) {
        const uint8_t b = uint8_t(c);
        if (b < 0x80) {
            out += c;
        } else {
            out += char(0xc0 | (b >> 6));
            out += char(0x80 | (b & 0x3f));
        }
    }
    return out;
}

std::string printableBytes(std::string_view bytes, size_t maxBytes) {
    static const char kHex[] = "0123456789abcdef";
    std::string shown;
    for (size_t i = 0; i < bytes.size() && i < maxBytes; ++i) {
        const uint8_t b = uint8_t(bytes[i]);
        if (b >= 0x20 && b < 0x7f) {
            shown += char(b);
        } else {
            shown += "\\x";
            shown += kHex[b >> 4];
            shown += kHex[b & 15];
        }
    }
    return shown;
}

} // namespace prt
