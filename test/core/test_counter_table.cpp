// The engine's counter table (models/counters.h) against EngineCounters and the docs: every
// counter once, the fix and aiding lists drawn from it, docs/node.md's table of the counters row
// by row, and the drops of propagate_bag's summary as docs/bag_tools.md names them.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "attitude_propagator/models/counters.h"
#include "attitude_propagator/models/outcome_table.h"
#include "package_files.h"

namespace ap = attitude_propagator;
namespace fs = std::filesystem;

namespace {

using package_files::packageRoot;
using package_files::readFile;

/// The part of `text` from the heading `heading` to the next heading of its level.
std::string section(const std::string& text, const std::string& heading) {
  const auto start = text.find("\n" + heading + "\n");
  if (start == std::string::npos) return "";
  return text.substr(start, text.find("\n## ", start + 1) - start);
}

/// The cells of a Markdown table row ("| a | b |"), trimmed; empty for any other line.
std::vector<std::string> cells(const std::string& line) {
  std::vector<std::string> out;
  if (line.rfind("| ", 0) != 0) return out;
  std::string cell;
  for (std::size_t i = 1; i < line.size(); ++i) {
    if (line[i] == '\\' && i + 1 < line.size() && line[i + 1] == '|') {
      cell += '|';  // an escaped bar inside a cell
      ++i;
    } else if (line[i] == '|') {
      out.push_back(cell.substr(1, cell.size() >= 2 ? cell.size() - 2 : 0));
      cell.clear();
    } else {
      cell += line[i];
    }
  }
  return out;
}

/// `text` without its backquotes (the docs quote names the table gives plain).
std::string unquoted(std::string text) {
  text.erase(std::remove(text.begin(), text.end(), '`'), text.end());
  return text;
}

/// The rows of the table under `heading` whose first cell is a quoted name.
std::vector<std::vector<std::string>> tableRows(const std::string& text,
                                                const std::string& heading) {
  std::istringstream lines(section(text, heading));
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> row = cells(line);
    if (!row.empty() && row[0].rfind('`', 0) == 0) rows.push_back(row);
  }
  return rows;
}

/// The backquoted words between `from` and the next `until` after it.
std::vector<std::string> quotedNames(const std::string& text, const std::string& from,
                                     const std::string& until) {
  std::vector<std::string> names;
  const auto start = text.find(from);
  if (start == std::string::npos) return names;
  const auto end = text.find(until, start + from.size());
  for (auto open = text.find('`', start); open < end; open = text.find('`', open)) {
    const auto close = text.find('`', open + 1);
    names.push_back(text.substr(open + 1, close - open - 1));
    open = close + 1;
  }
  return names;
}

bool isAiding(const ap::CounterInfo& info) {
  return info.input == ap::CounterInput::Accel || info.input == ap::CounterInput::Mag;
}

}  // namespace

// Each field of EngineCounters is reached by exactly one row: a distinct value set through each
// row reads back through that row alone, and the rows account for every counter the struct
// holds (its size: its own counters and the two AidingCounters, nothing else).
TEST(CounterTable, EveryCounterOnce) {
  const auto& table = ap::engineCounterTable();
  ap::EngineCounters c;
  for (std::size_t i = 0; i < table.size(); ++i) ap::counterField(c, table[i]) = i + 1;
  std::set<std::string> names;
  for (std::size_t i = 0; i < table.size(); ++i) {
    EXPECT_EQ(ap::counterValue(c, table[i]), i + 1) << table[i].name << ": another row's field";
    EXPECT_TRUE(names.insert(table[i].name).second) << table[i].name << " twice";
    EXPECT_FALSE(table[i].meaning.empty()) << table[i].name;
  }
  EXPECT_EQ(sizeof(ap::EngineCounters), table.size() * sizeof(std::uint64_t));
  EXPECT_EQ(sizeof(ap::AidingCounters), ap::aidingCounterTable().size() * sizeof(std::uint64_t));
}

// A field's name is its row's; the table names each field as the diagnostics always have (the
// rostests read the keys by these names).
TEST(CounterTable, NamesTheFieldsByTheirDiagnosticsKeys) {
  EXPECT_STREQ(ap::counterName(&ap::EngineCounters::dropped_stale), "dropped_stale");
  EXPECT_STREQ(ap::counterName(&ap::EngineCounters::jumps_back), "jumps_back");
  EXPECT_STREQ(ap::counterName(&ap::EngineCounters::bias_applied), "bias_applied");
  EXPECT_STREQ(ap::counterName(&ap::EngineCounters::fixes_over_budget), "fixes_over_budget");
  ap::EngineCounters c;
  c.accel.rejected_magnitude = 3;
  c.mag.not_aligned = 4;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    if (info.name == "accel_rejected_magnitude") {
      EXPECT_EQ(ap::counterValue(c, info), 3u);
    } else if (info.name == "mag_not_aligned") {
      EXPECT_EQ(ap::counterValue(c, info), 4u);
    }
  }
}

// The fix list and the fixes not applied follow the table: its fix rows, `fixes_` dropped, and
// the unused ones summed (docs/node.md's table of fixes: all but accepted and reset).
TEST(CounterTable, FixCountersAreTheTablesFixRows) {
  std::vector<std::string> fix_rows;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    if (info.input == ap::CounterInput::Fix) fix_rows.push_back(info.name);
  }
  ap::EngineCounters c;
  std::vector<std::string> listed;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) ap::counterField(c, info) = 100;
  c.fixes_accepted = 1;
  c.fixes_reset = 2;
  ap::forEachFixCounter(
      c, [&](const char* name, std::uint64_t) { listed.push_back(std::string("fixes_") + name); });
  EXPECT_EQ(listed, fix_rows);
  EXPECT_EQ(fix_rows.size(), 9u);
  EXPECT_EQ(ap::fixesNotApplied(c), 7u * 100u);  // seven ways a fix is not applied
}

// The aiding counters appear under accel_ and mag_ in AidingCounters' own order.
TEST(CounterTable, AidingRowsFollowTheAidingTable) {
  std::vector<std::string> accel, mag, expected_accel, expected_mag;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    if (info.input == ap::CounterInput::Accel) accel.push_back(info.name);
    if (info.input == ap::CounterInput::Mag) mag.push_back(info.name);
  }
  ap::AidingCounters{}.forEach([&](const char* name, std::uint64_t) {
    expected_accel.push_back(std::string("accel_") + name);
    expected_mag.push_back(std::string("mag_") + name);
  });
  EXPECT_EQ(accel, expected_accel);
  EXPECT_EQ(mag, expected_mag);
}

// docs/node.md's table of the counters is the table, row by row: name, input, kind, meaning,
// nothing more and nothing less (the accel_*/mag_* rows are the Gravity and north table's).
TEST(CounterTable, NodeDocsListEveryCounter) {
  const std::string text = readFile(packageRoot() / "docs" / "node.md");
  const auto rows = tableRows(text, "## Counters");
  std::vector<std::vector<std::string>> expected;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    if (isAiding(info)) continue;
    expected.push_back({info.name, ap::counterInputName(info.input), ap::counterKindName(info.kind),
                        info.meaning});
  }
  std::vector<std::vector<std::string>> documented;
  for (const auto& row : rows) {
    std::vector<std::string> plain;
    for (const std::string& cell : row) plain.push_back(unquoted(cell));
    documented.push_back(plain);
  }
  EXPECT_EQ(documented, expected) << "docs/node.md, ## Counters: not the core's table";
}

// docs/node.md's table of the gravity and field counters gives AidingCounters' names and
// meanings, in its order.
TEST(CounterTable, NodeDocsListEveryAidingCounter) {
  const std::string text = readFile(packageRoot() / "docs" / "node.md");
  std::vector<std::vector<std::string>> documented, expected;
  for (const auto& row : tableRows(text, "## Gravity and north (use_accel, use_mag)")) {
    documented.push_back({unquoted(row.at(0)), unquoted(row.at(1))});
  }
  for (const ap::AidingCounterInfo& info : ap::aidingCounterTable()) {
    expected.push_back({info.name, info.meaning});
  }
  EXPECT_EQ(documented, expected);
}

// docs/bag_tools.md names propagate_bag's drops as the summary prints them: the unused rate and
// torque counters, in the table's order.
TEST(CounterTable, BagToolsDocsNameTheDropsAsTheTable) {
  const std::string text = readFile(packageRoot() / "docs" / "bag_tools.md");
  std::vector<std::string> drops;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    if (ap::countsUnusedInput(info)) drops.push_back(info.name);
  }
  EXPECT_EQ(quotedNames(text, "under the node's diagnostics keys (", ":"), drops);
  EXPECT_EQ(drops.size(), 12u);
}

// The unused counters of the rates and torques, with `accepted`, account for `received`: the
// kinds say so of exactly these rows.
TEST(CounterTable, ReceivedIsTheRatesAndTorques) {
  std::vector<std::string> received, used;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    const bool input =
        info.input == ap::CounterInput::RateOrTorque || info.input == ap::CounterInput::Rate;
    if (info.kind == ap::CounterKind::Received) received.push_back(info.name);
    if (input && info.kind == ap::CounterKind::Used) used.push_back(info.name);
  }
  EXPECT_EQ(received, std::vector<std::string>{"received"});
  EXPECT_EQ(used, std::vector<std::string>{"accepted"});
}

// docs/node.md's table of what becomes of a fix names, in its last column, the counter of every
// fix outcome that counts one (models/outcome_table.h): the docs say what the engine counts.
TEST(CounterTable, NodeMdsTableOfFixesNamesEveryFixOutcomesCounter) {
  const std::string doc = readFile(packageRoot() / "docs/node.md");
  const std::size_t begin = doc.find("| fix | outcome | counted in diagnostics as |");
  ASSERT_NE(begin, std::string::npos) << "docs/node.md: the table of fixes";
  const std::string table = doc.substr(begin, doc.find("\n\n", begin) - begin);
  for (const ap::FixOutcomeRow& row : ap::fixOutcomeTable()) {
    for (const auto field : row.counters) {
      const std::string name = std::string("`") + ap::counterName(field) + "`";
      EXPECT_NE(table.find(name), std::string::npos) << name << " (" << row.name << ")";
    }
  }
}
