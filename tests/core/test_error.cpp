// printable (core/error.hpp): what an error line may carry of a file's bytes.
#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"

namespace {

using hfbake::printable;

TEST(Printable, ControlBytesAreEscaped) {
  EXPECT_EQ(printable("a\nb\rc\x7f"), "a\\x0ab\\x0dc\\x7f");
  EXPECT_EQ(printable(std::string("a\0b", 3)), "a\\x00b");
}

TEST(Printable, WellFormedUtf8IsKept) {
  const std::string text = "h\xc3\xa9ight \xe2\x80\x94 \xf0\x9f\x8c\x8b";  // é, an em dash, U+1F30B
  EXPECT_EQ(printable(text), text);
}

// A Latin-1 byte, a lone continuation byte, a truncated sequence, an overlong form, a surrogate and a code
// point beyond U+10FFFF are not UTF-8: each byte that is not part of a well-formed sequence is escaped.
TEST(Printable, IllFormedUtf8IsEscaped) {
  EXPECT_EQ(printable("x\xff.png"), "x\\xff.png");
  EXPECT_EQ(printable("caf\xe9"), "caf\\xe9");
  EXPECT_EQ(printable("\x80"), "\\x80");
  EXPECT_EQ(printable("\xe2\x80"), "\\xe2\\x80");
  EXPECT_EQ(printable("\xc0\xaf"), "\\xc0\\xaf");
  EXPECT_EQ(printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");
  EXPECT_EQ(printable("\xf4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");
  EXPECT_EQ(printable("\xc3\xa9\xff\xc3\xa9"), "\xc3\xa9\\xff\xc3\xa9");
}

}  // namespace
