#include "utf8.h"

#include <gtest/gtest.h>

#include <string>

namespace prt {
namespace {

TEST(Utf8, WellFormedSequencesPassAndEveryKindOfMalformedOneFails) {
    EXPECT_TRUE(isUtf8(""));
    EXPECT_TRUE(isUtf8("plain ASCII"));
    EXPECT_TRUE(isUtf8("Terraind\xc3\xa6k"));           // U+00E6
    EXPECT_TRUE(isUtf8("\xe2\x82\xac"));                // U+20AC
    EXPECT_TRUE(isUtf8("\xf0\x9f\x98\x80"));            // U+1F600
    EXPECT_TRUE(isUtf8("\xf4\x8f\xbf\xbf"));            // U+10FFFF, the last code point
    EXPECT_TRUE(isUtf8(std::string("a\0b", 3)));        // NUL is a code point
    EXPECT_FALSE(isUtf8("Terraind\xe6k"));              // Latin-1
    EXPECT_FALSE(isUtf8("\x80"));                       // a stray continuation byte
    EXPECT_FALSE(isUtf8("\xc3"));                       // cut short
    EXPECT_FALSE(isUtf8("\xe2\x82"));                   // cut short
    EXPECT_FALSE(isUtf8("\xc0\xaf"));                   // overlong '/'
    EXPECT_FALSE(isUtf8("\xe0\x80\xaf"));               // overlong '/'
    EXPECT_FALSE(isUtf8("\xf0\x80\x80\xaf"));           // overlong '/'
    EXPECT_FALSE(isUtf8("\xed\xa0\x80"));               // U+D800, a surrogate
    EXPECT_FALSE(isUtf8("\xf4\x90\x80\x80"));           // U+110000
    EXPECT_FALSE(isUtf8("\xf5\x80\x80\x80"));
    EXPECT_FALSE(isUtf8("\xe2\x28\xa1"));               // a lead byte followed by ASCII
}

TEST(Utf8, Latin1IsTranscodedAndUtf8KeptAsItIs) {
    EXPECT_EQ(utf8FromLatin1("Terraind\xe6k"), "Terraind\xc3\xa6k");
    EXPECT_EQ(utf8FromLatin1("\xff\x80 x"), "\xc3\xbf\xc2\x80 x");
    EXPECT_EQ(utf8FromLatin1("Terraind\xc3\xa6k"), "Terraind\xc3\xa6k"); // already UTF-8: unchanged
    EXPECT_EQ(utf8FromLatin1("ascii"), "ascii");
    // Whatever the bytes, the result is UTF-8.
    std::string every;
    for (int b = 1; b < 256; ++b) every += char(b);
    EXPECT_TRUE(isUtf8(utf8FromLatin1(every)));
    EXPECT_EQ(utf8FromLatin1(every).size(), 127u + 2u * 128u);
}

// A message shows any bytes as printable ASCII: control bytes (ESC, DEL, NUL) and every byte past 0x7f escaped.
TEST(Utf8, PrintableBytesEscapesEverythingButPrintableAscii) {
    EXPECT_EQ(printableBytes("name-1 ok"), "name-1 ok");
    EXPECT_EQ(printableBytes("Terraind\xe6k"), "Terraind\\xe6k");
    EXPECT_EQ(printableBytes(std::string("a\x1b[2Jb\x7f\0c", 9)), "a\\x1b[2Jb\\x7f\\x00c");
    EXPECT_EQ(printableBytes("\xff\t", 200), "\\xff\\x09");
    EXPECT_EQ(printableBytes("abcdef", 3), "abc");
}

} // namespace
} // namespace prt
