// Tests of the text helpers that have no reader of their own to be tested through.
#include "foveal/util/text.h"

#include <gtest/gtest.h>

using foveal::text::printable;

// Valid UTF-8 is kept whole; what is not (RFC 3629: a stray continuation byte, an overlong form, a
// surrogate, past U+10FFFF, a sequence cut short) and control characters become \xNN, byte by byte
TEST(Text, PrintableKeepsUtf8AndEscapesTheRest) {
  EXPECT_EQ(printable("gaze 2.5\xC2\xB0, 840\xC3\x97"
                      "525, \xE6\x97\xA5\xE6\x9C\xAC, \xF0\x9F\x91\x81"),
            "gaze 2.5\xC2\xB0, 840\xC3\x97"
            "525, \xE6\x97\xA5\xE6\x9C\xAC, \xF0\x9F\x91\x81");
  EXPECT_EQ(printable("caf\xE9.png"), "caf\\xe9.png");               // Latin-1, not UTF-8
  EXPECT_EQ(printable("a\nb\tc\x7F"), "a\\x0ab\\x09c\\x7f");         // one line
  EXPECT_EQ(printable("\xC0\xAF"), "\\xc0\\xaf");                    // overlong '/'
  EXPECT_EQ(printable("\xE0\x80\xAF"), "\\xe0\\x80\\xaf");           // overlong, three bytes
  EXPECT_EQ(printable("\xED\xA0\x80"), "\\xed\\xa0\\x80");           // a surrogate, U+D800
  EXPECT_EQ(printable("\xF4\x90\x80\x80"), "\\xf4\\x90\\x80\\x80");  // past U+10FFFF
  EXPECT_EQ(printable("x\xE2\x82"), "x\\xe2\\x82");                  // cut short at the end
  EXPECT_EQ(printable("\xE2\x82"
                      "A"),
            "\\xe2\\x82A");                        // cut short before ASCII
  EXPECT_EQ(printable("\x80\xBF"), "\\x80\\xbf");  // continuation bytes alone
  EXPECT_EQ(printable(std::string_view("a\0b", 3)), "a\\x00b");
  EXPECT_EQ(printable(""), "");
}
