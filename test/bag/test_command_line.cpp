// The tools' one option parser (src/tools/command_line.h) on its own, against the habits the
// tools document (docs/bag_tools.md, "Options"): `--key value` and `--key=value` alike, each
// option's values from the words after it, the inputs in order, a usage error naming the
// option, and the help laid out in two columns from the table.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../../src/tools/command_line.h"
#include "../../src/tools/tool_error.h"

namespace tools = attitude_propagator::tools;

namespace {

/// What a table of every kind of row sets.
struct Set {
  std::string output;
  std::vector<std::string> pair;
  bool flag = false;
};

tools::CommandLine table(Set& set) {
  return {"tool (attitude_propagator) 0.0.0",
          10,
          {tools::helpParagraph("usage: tool IN [options]\n\n"),
           tools::valueOption("-o, --output", "OUT", "the output\nsecond line",
                              [&set](const std::string& v) { set.output = v; }),
           tools::valuesOption("--pair", "A B", "two values",
                               [&set](const std::vector<std::string>& v) { set.pair = v; }),
           tools::flagOption("--flag", "a flag", [&set] { set.flag = true; }),
           tools::helpOption("this text"), tools::helpParagraph("\nthe end\n")}};
}

/// The inputs parseCommandLine returns for `words` (argv[0] first, as main gets it).
std::vector<std::string> parse(Set& set, std::vector<std::string> words) {
  words.insert(words.begin(), "tool");
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(&w[0]);
  return tools::parseCommandLine(table(set), static_cast<int>(argv.size()), argv.data());
}

/// The message of the UsageError parsing `words` throws; empty when none is thrown.
std::string usageError(std::vector<std::string> words) {
  Set set;
  try {
    parse(set, std::move(words));
  } catch (const tools::UsageError& e) {
    EXPECT_EQ(e.exit_code, tools::kExitUsage);
    return e.what();
  }
  return "";
}

TEST(CommandLine, OptionsTakeTheirValuesAndTheRestAreInputsInOrder) {
  Set set;
  const auto inputs = parse(set, {"a.bag", "-o", "x.bag", "b.bag", "--pair", "p", "q", "--flag"});
  EXPECT_EQ(inputs, (std::vector<std::string>{"a.bag", "b.bag"}));
  EXPECT_EQ(set.output, "x.bag");
  EXPECT_EQ(set.pair, (std::vector<std::string>{"p", "q"}));
  EXPECT_TRUE(set.flag);
}

// A long spelling is split at its first '=' (the value may hold more); a short one is a word
// as given, as before the table.
TEST(CommandLine, KeyEqualsValueIsTheOptionAndItsValue) {
  Set set;
  const auto inputs = parse(set, {"--output=y=z.bag", "--pair=p", "q", "a.bag"});
  EXPECT_EQ(inputs, std::vector<std::string>{"a.bag"});
  EXPECT_EQ(set.output, "y=z.bag");
  EXPECT_EQ(set.pair, (std::vector<std::string>{"p", "q"}));
  EXPECT_EQ(usageError({"-o=x"}), "-o=x: unknown option (see --help)");
}

TEST(CommandLine, UsageErrorsNameTheOption) {
  EXPECT_EQ(usageError({"a.bag", "--bogus"}), "--bogus: unknown option (see --help)");
  EXPECT_EQ(usageError({"a.bag", "-o"}), "-o: needs a value");
  EXPECT_EQ(usageError({"a.bag", "--output", ""}), "--output: an empty value");
  EXPECT_EQ(usageError({"a.bag", "--pair", "p"}), "--pair: needs 2 values (A B)");
  EXPECT_EQ(usageError({"a.bag", "--pair", "p", ""}), "--pair: an empty value");
  EXPECT_EQ(usageError({"a.bag", "-"}), "-: unknown option (see --help)");
  EXPECT_EQ(usageError({"a.bag", "--output=x", "--flag"}), "");
}

TEST(CommandLine, HelpIsTheTableInTwoColumns) {
  Set set;
  EXPECT_EQ(tools::helpText(table(set)),
            "usage: tool IN [options]\n"
            "\n"
            "  -o, --output OUT\n"
            "             the output\n"
            "             second line\n"
            "  --pair A B two values\n"
            "  --flag     a flag\n"
            "  -h, --help this text\n"
            "\n"
            "the end\n");
}

}  // namespace
