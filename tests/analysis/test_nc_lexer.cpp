// SPDX-License-Identifier: MIT
// The NC lexer every reader shares (nc_lexer.hpp): comments and a word's number, and the program reader
// and the interpreter saying the same of the same malformed number.
#include <gtest/gtest.h>

#include <string>

#include "ballbar/analysis/nc_interpreter.hpp"
#include "ballbar/analysis/nc_lexer.hpp"
#include "ballbar/analysis/nc_program.hpp"

namespace ballbar::analysis {
namespace {

TEST(NcLexer, CommentsAreFoundAndALineWithoutOneIsNotCopied) {
    std::string buffer, comment;
    const std::string_view plain = "G1 X1 Y2";
    EXPECT_EQ(split_nc_comments(plain, 1, true, buffer, comment).data(), plain.data()) << "no copy";
    EXPECT_EQ(split_nc_comments("G1 (to the corner) X1 ; fast", 1, true, buffer, comment), "G1  X1 ");
    EXPECT_EQ(comment, "to the corner fast");
    comment.clear();
    EXPECT_EQ(split_nc_comments("G1 X1 ; not a comment in Fanuc", 1, false, buffer, comment),
              "G1 X1 ; not a comment in Fanuc");
    try {
        (void)split_nc_comments("G1 (open", 7, true, buffer, comment);
        FAIL() << "accepted";
    } catch (const NcError& e) {
        EXPECT_EQ(e.line(), 7);
        EXPECT_NE(std::string(e.what()).find("is not closed"), std::string::npos) << e.what();
    }
}

TEST(NcLexer, AWordsNumberIsAPlainDecimal) {
    auto read = [](std::string_view text) {
        std::size_t pos = 0;
        const double v = read_nc_number(text, pos, 1, 'X');
        EXPECT_TRUE(pos == text.size() || text[pos] == ' ') << text;
        return v;
    };
    EXPECT_EQ(read("12.5"), 12.5);
    EXPECT_EQ(read("-0.001"), -0.001);
    EXPECT_EQ(read("+.5"), 0.5);
    EXPECT_EQ(read(".25 Y1"), 0.25);
    EXPECT_EQ(read("-7"), -7.0);
    const struct {
        const char* text;
        const char* says;
    } bad[] = {{"", "has no number"},
               {"-", "has no number"},
               {"1e5", "without an exponent"},
               {"1..2", "malformed or out-of-range number '1..2'"},
               {"2000000000", "malformed or out-of-range number"}};
    for (const auto& b : bad) {
        std::size_t pos = 0;
        try {
            (void)read_nc_number(b.text, pos, 3, 'X');
            ADD_FAILURE() << "accepted " << b.text;
        } catch (const NcError& e) {
            EXPECT_NE(std::string(e.what()).find(b.says), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("word X"), std::string::npos) << e.what();
        }
    }
}

TEST(NcLexer, TheReadersSayTheSameOfTheSameNumber) {
    const std::string program = "%\nO0001\nG90\nG1 X1..2 Y0 Z0 A0 C0 F100\nM30\n%\n";
    std::string from_reader, from_interpreter;
    try {
        (void)parse_nc_program(program, NcDialect::Fanuc);
    } catch (const NcError& e) {
        from_reader = e.what();
    }
    try {
        NcInterpreter in(program, {});
        NcStep step;
        while (in.next(step)) {
        }
    } catch (const NcError& e) {
        from_interpreter = e.what();
    }
    EXPECT_FALSE(from_reader.empty());
    EXPECT_EQ(from_reader, from_interpreter);
}

}  // namespace
}  // namespace ballbar::analysis
