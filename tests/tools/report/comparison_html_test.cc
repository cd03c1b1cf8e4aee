// The comparison pages' rules (tools/report/comparison_html.cc): which solvers tie, wide tables
// split into blocks of columns, the glossary of every term the pages use.
#include "tools/report/comparison_html.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "tests/support/text_count.h"
#include "tools/report/comparison_tables.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

size_t Count(const std::string& text, const std::string& what) {
  return testing::CountOccurrences(text, what);
}

TEST(ComparisonHtml, SolversWithinTheFractionTieForTheBest) {
  EXPECT_EQ(TiedBest({0.100, 0.104, 0.106, std::nan("")}, 0.05), (std::vector<size_t>{0, 1}));
  EXPECT_EQ(TiedBest({0.2, 0.1, 0.1}, 0.0), (std::vector<size_t>{1, 2}));
  EXPECT_TRUE(TiedBest({std::nan(""), INFINITY}, 0.05).empty());
}

TEST(ComparisonHtml, WideTablesSplitIntoBlocksRepeatingTheNamingColumns) {
  TextTable table;
  table.title = "per image";
  table.header = {"image", "solver"};
  for (int c = 0; c < 14; ++c) table.header.push_back("c" + std::to_string(c));
  std::vector<std::string> row = {"img_1", "taylor"};
  for (int c = 0; c < 14; ++c) row.push_back(std::to_string(c));
  table.rows = {row};
  table.notes = {"a note"};
  const std::string html = RenderHtmlTable(table);
  EXPECT_EQ(Count(html, "<table>"), 2u);
  EXPECT_EQ(Count(html, "<td>img_1</td><td>taylor</td>"), 2u);
  EXPECT_NE(html.find("<caption>per image (continued)</caption>"), std::string::npos);
  EXPECT_EQ(Count(html, "<li>a note</li>"), 1u);
  // 14 value columns in two blocks of 7.
  EXPECT_LT(html.find("<th>c6</th>"), html.find("(continued)"));
  EXPECT_GT(html.find("<th>c7</th>"), html.find("(continued)"));
  // A narrow table stays one.
  table.header.resize(5);
  EXPECT_EQ(Count(RenderHtmlTable(table), "<table>"), 1u);
}

// The page names micro units as µs and µm; the table as the console and Markdown hold it keeps
// the ASCII names.
TEST(ComparisonHtml, MicroUnitsReadAsMicroOnThePage) {
  TextTable table;
  table.header = {"solver", "time (us)", "refine (us)", "residual (um)", "pos RMSE (mm)"};
  table.rows = {{"taylor", "12.5", "3.1", "0.42", "1.0"}};
  const std::string html = RenderHtmlTable(table);
  EXPECT_NE(html.find("<th>time (\u00b5s)</th><th>refine (\u00b5s)</th><th>residual "
                      "(\u00b5m)</th><th>pos RMSE (mm)</th>"),
            std::string::npos)
      << html;
  EXPECT_EQ(table.header[1], "time (us)");
  EXPECT_NE(RenderText(table).find("time (us)"), std::string::npos);
}

TEST(ComparisonHtml, TheGlossaryExplainsEveryTermThePagesUse) {
  const std::string glossary = ComparisonGlossaryHtml();
  for (const char* term : {"taylor_as_printed", "taylor", "ceres_analytic", "ceres_autodiff",
                           "huber", "NEES", "nees_ap", "t/ref", "eq. 21", "success"})
    EXPECT_NE(glossary.find(term), std::string::npos) << term;
  EXPECT_EQ(glossary.rfind("<dl class=\"glossary\">", 0), 0u);
}


// Every column of every comparison table is in the glossary, its unit left out ("pos RMSE (cm)":
// "pos RMSE"); the columns that only name a thing (solver, image, status, coordinates, angles) aside.
TEST(ComparisonHtml, TheGlossaryExplainsEveryColumnOfTheTables) {
  MonteCarloOptions options;
  MonteCarloResult monte_carlo;
  monte_carlo.solver_names = {"taylor"};
  monte_carlo.settings.resize(1);
  monte_carlo.settings[0].solvers.resize(1);
  monte_carlo.settings[0].solvers[0].solver = "taylor";
  DatasetComparisonResult dataset;
  dataset.solver_names = {"taylor"};
  dataset.reference_solver = "taylor";
  dataset.has_reference = true;
  dataset.summaries.resize(1);
  BlockComparisonOptions block_options;
  BlockComparisonResult blocks;
  blocks.settings.resize(1);
  blocks.solver_names = {"taylor"};
  blocks.statistics = {{BlockSolverStatistics()}};
  BlockDatasetResult block;
  block.solvers.resize(1);
  std::vector<TextTable> tables = MonteCarloTables(options, monte_carlo);
  for (const TextTable& t : DatasetTables(dataset)) tables.push_back(t);
  for (const TextTable& t : BlockComparisonTables(block_options, blocks)) tables.push_back(t);
  tables.push_back(BlockDatasetTable(block));
  const std::string glossary = ComparisonGlossaryHtml();
  const std::set<std::string> naming = {"solver", "image",       "status",    "result", "X",
                                        "Y",      "Z",           "omega",     "phi",    "kappa",
                                        "inliers"};
  size_t columns = 0;
  for (const TextTable& table : tables)
    for (const std::string& header : table.header) {
      const std::string name = header.substr(0, header.find(" ("));
      if (naming.count(name)) continue;
      ++columns;
      EXPECT_NE(glossary.find(HtmlEscape(name)), std::string::npos) << header;
    }
  EXPECT_GE(columns, 30u);
}

// The block page's verdict at the baseline: among the solvers that adjusted the most blocks, those
// within 5 % of the best camera RMSE tie, and the fastest of them is the one to use; a solver that
// failed blocks is named in the findings and cannot be recommended however accurate.
TEST(ComparisonHtml, TheBlockVerdictRecommendsTheFastestOfTheTiedSolvers) {
  BlockComparisonOptions options;
  options.trials = 4;
  BlockComparisonResult result;
  result.settings = {BlockSetting()};
  result.solver_names = {"taylor", "ceres_analytic", "ceres_autodiff", "lucky"};
  auto solver = [](int successes, double rmse_m, double seconds) {
    BlockSolverStatistics st;
    st.trials = 4;
    st.successes = successes;
    st.camera_rmse_m = rmse_m;
    st.mean_seconds = seconds;
    return st;
  };
  // taylor and ceres_analytic tie (0.0100 and 0.0104 m), ceres_autodiff is 10 % off, lucky is the
  // most accurate but failed a block.
  result.statistics = {{solver(4, 0.0100, 0.030), solver(4, 0.0104, 0.020),
                        solver(4, 0.0110, 0.001), solver(3, 0.0050, 0.001)}};
  const std::string html = BlockComparisonHtml(options, result, "photopose compare");
  const size_t verdict = html.find("<div class=\"verdict");
  ASSERT_NE(verdict, std::string::npos) << html;
  const std::string text = html.substr(verdict, html.find("</div>", verdict) - verdict);
  for (const char* expected :
       {"<b>Use ceres_analytic.</b>",
        "<b>taylor</b> and <b>ceres_analytic</b> tie for the most accurate",
        "ceres_analytic is the fastest of them (20 ms per block)",
        "<b>lucky</b> failed 1 of 4 blocks."})
    EXPECT_NE(text.find(expected), std::string::npos) << expected << " in " << text;
  EXPECT_EQ(text.find("<b>ceres_autodiff</b>"), std::string::npos) << text;
  EXPECT_NE(text.find("verdict note"), std::string::npos) << "findings make it a note: " << text;
  // The command that made the page is on it, escaped, as on the other comparison pages.
  const std::string run = BlockComparisonHtml(options, result, "photopose compare --trials=4 <x>");
  EXPECT_NE(run.find("<code>photopose compare --trials=4 &lt;x&gt;</code>"), std::string::npos);
  // No solver adjusted a block: none is recommended.
  for (BlockSolverStatistics& st : result.statistics[0]) st.successes = 0;
  const std::string none = BlockComparisonHtml(options, result, "photopose compare");
  EXPECT_NE(none.find("<b>No solver adjusted a block at the baseline.</b>"), std::string::npos);
  EXPECT_EQ(none.find("<b>Use "), std::string::npos);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
