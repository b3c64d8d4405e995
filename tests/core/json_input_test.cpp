// Untrusted JSON (json_input.h): the shape check before any parse, excerpts in messages, typed members.
#include "json_input.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace {

// The message of the prt::Error `f` throws, or "" when it throws none.
template <class F>
std::string errorOf(F f, int* exitCode = nullptr) {
    try {
        f();
    } catch (const prt::Error& e) {
        if (exitCode) *exitCode = e.exitCode();
        return e.what();
    }
    return "";
}

} // namespace

TEST(JsonInput, ShapeCheckRefusesDeepNestingWithoutRecursingAndAcceptsItsLimit) {
    // 100,000 nested arrays: refused at the first level past the limit, at its byte.
    std::string deep(100000, '[');
    deep += std::string(100000, ']');
    int code = 0;
    std::string message = errorOf([&] { prt::checkJsonShape(deep, "f.json", "", 1 << 20); }, &code);
    EXPECT_NE(message.find("deeper than 64 levels (at byte 64)"), std::string::npos) << message;
    EXPECT_EQ(code, prt::kExitInput);
    // Exactly at the limit, objects and arrays mixed: accepted.
    std::string atLimit;
    for (int i = 0; i < 32; ++i) atLimit += "{\"a\":[";
    atLimit += "1";
    for (int i = 0; i < 32; ++i) atLimit += "]}";
    EXPECT_EQ(errorOf([&] { prt::checkJsonShape(atLimit, "f.json", "", 1 << 20); }), "");
    EXPECT_NE(errorOf([&] { prt::checkJsonShape("[" + atLimit + "]", "f.json", "", 1 << 20); }), "");
}

TEST(JsonInput, ShapeCheckIgnoresBracketsInsideStringsAndEscapes) {
    // 1,000 brackets inside a string, an escaped quote and an escaped backslash before the closing quote.
    std::string text = "{\"a\": \"" + std::string(1000, '[') + "\\\"[[[\\\\\", \"b\": [1]}";
    EXPECT_EQ(errorOf([&] { prt::checkJsonShape(text, "f.json", "", 1 << 20, 2); }), "");
    EXPECT_EQ(prt::parseJsonBounded(text, "f.json", "", 1 << 20, 2)["b"][0], 1);
    // The escape \\ ends with the string still open only if the scanner mishandles it: here the next [ counts.
    EXPECT_NE(errorOf([&] { prt::checkJsonShape("[\"\\\\\", [[1]]]", "f.json", "", 1 << 20, 2); }), "");
}

TEST(JsonInput, SizeIsBoundedBeforeTheFileIsRead) {
    std::string path = (std::filesystem::temp_directory_path() / ("prt_json_input_" + std::to_string(getpid()))).string();
    std::ofstream(path) << "[" << std::string(4096, ' ') << "]";
    std::string message = errorOf([&] { prt::readJsonFile(path, 1000); });
    EXPECT_NE(message.find("file of 4098 bytes, above the limit of 1000 bytes"), std::string::npos) << message;
    EXPECT_EQ(prt::readJsonFile(path, 5000).size(), 0u);
    std::ofstream(path) << "{\"a\": ";
    EXPECT_NE(errorOf([&] { prt::readJsonFile(path, 5000); }).find("not JSON"), std::string::npos);
    std::filesystem::remove(path);
    EXPECT_NE(errorOf([&] { prt::readJsonFile(std::filesystem::temp_directory_path().string(), 5000); }).find("folder"),
              std::string::npos);
}

TEST(JsonInput, ExcerptCutsLongValuesToEightyCharacters) {
    nlohmann::json big = nlohmann::json::array();
    for (int i = 0; i < 10000; ++i) big.push_back(i);
    std::string excerpt = prt::jsonExcerpt(big);
    EXPECT_EQ(excerpt.size(), 83u);
    EXPECT_EQ(excerpt.substr(0, 8), "[0,1,2,3");
    EXPECT_EQ(excerpt.substr(80), "...");
    EXPECT_EQ(prt::jsonExcerpt(nlohmann::json("short")), "\"short\"");
    // Invalid UTF-8 inside a string is replaced, not thrown about.
    EXPECT_NO_THROW(prt::jsonExcerpt(nlohmann::json(std::string("\xff\xfe", 2))));
}

TEST(JsonInput, TypedMembersNameTheFileTheKeyAndTheTypeExpected) {
    nlohmann::json doc = nlohmann::json::parse(R"({"format": 5, "hash": "x", "order": 4294967299, "big": 1e300,
                                                   "neg": -3, "huge": 18446744073709551615, "flag": 1, "o": {"k": [1]}})");
    EXPECT_EQ(errorOf([&] { prt::jsonString(doc, "format", "l.json", ""); }),
              "l.json: format: expected a string, got an integer 5");
    EXPECT_EQ(prt::jsonString(doc, "hash", "l.json", ""), "x");
    EXPECT_EQ(errorOf([&] { prt::jsonString(doc, "missing", "l.json", "input"); }), "l.json: input.missing: is missing");
    EXPECT_EQ(errorOf([&] { prt::jsonString(doc["o"], "k", "l.json", "o"); }),
              "l.json: o.k: expected a string, got an array [1]");
    EXPECT_EQ(errorOf([&] { prt::jsonString(nlohmann::json(3), "k", "l.json", "input"); }),
              "l.json: input: expected an object, got an integer 3");
    // 2^32 + 3 is refused by the range, not wrapped to 3.
    EXPECT_EQ(errorOf([&] { prt::jsonInteger(doc, "order", "l.json", "", 1, 32); }),
              "l.json: order: expected an integer in 1..32, got 4294967299");
    EXPECT_EQ(errorOf([&] { prt::jsonInteger(doc, "neg", "l.json", "", 0, 10); }),
              "l.json: neg: expected an integer in 0..10, got -3");
    EXPECT_NE(errorOf([&] { prt::jsonInteger(doc, "huge", "l.json", "", 0, INT64_MAX); }), "");
    EXPECT_NE(errorOf([&] { prt::jsonInteger(doc, "big", "l.json", "", 0, 10); }).find("expected an integer"),
              std::string::npos);
    EXPECT_EQ(prt::jsonInteger(doc, "neg", "l.json", "", -5, 10), -3);
    EXPECT_EQ(prt::jsonNumber(doc, "big", "l.json", ""), 1e300);
    EXPECT_NE(errorOf([&] { prt::jsonFloat(doc, "big", "l.json", ""); }).find("outside the float range"),
              std::string::npos);
    EXPECT_EQ(errorOf([&] { prt::jsonBool(doc, "flag", "l.json", ""); }),
              "l.json: flag: expected true or false, got an integer 1");
}
