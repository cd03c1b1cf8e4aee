#include "tools/report/html_kit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <regex>
#include <string>
#include <vector>

#include "tests/support/text_count.h"

namespace photopose::cli {
namespace PHOTOPOSE_UNITY_ID {

size_t Count(const std::string& text, const std::string& what) {
  return testing::CountOccurrences(text, what);
}

TEST(HtmlKit, EscapesTheFiveSpecialCharacters) {
  EXPECT_EQ(HtmlEscape("a<b & \"c\" 'd' > e"), "a&lt;b &amp; &quot;c&quot; &#39;d&#39; &gt; e");
  EXPECT_EQ(HtmlEscape("plain text, 1.5 m"), "plain text, 1.5 m");
  EXPECT_EQ(HtmlEscape("&amp;"), "&amp;amp;");  // not idempotent: escape once
}

TEST(HtmlKit, NumbersSayNaWhenNotFinite) {
  EXPECT_EQ(ReportNumber(0.0123456), "0.0123");
  EXPECT_EQ(ReportNumber(2.5, "%g"), "2.5");
  EXPECT_EQ(ReportNumber(std::nan("")), "n/a");
}

TEST(HtmlKit, PageHeadIsWellFormed) {
  const std::string page = HtmlPageOpen("a <title>", "a & heading") + HtmlPageClose();
  EXPECT_EQ(page.rfind("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">", 0),
            0u);
  EXPECT_NE(page.find("<title>a &lt;title&gt;</title>"), std::string::npos);
  EXPECT_NE(page.find("<h1>a &amp; heading</h1>"), std::string::npos);
  // One screen stylesheet and one print stylesheet, both inside the head, the body after it.
  EXPECT_EQ(Count(page, "<style>"), 1u);
  EXPECT_EQ(Count(page, "<style media=\"print\">"), 1u);
  EXPECT_EQ(Count(page, "</style>"), 2u);
  const size_t head_end = page.find("</head>");
  ASSERT_NE(head_end, std::string::npos);
  EXPECT_LT(page.rfind("</style>"), head_end);
  EXPECT_LT(head_end, page.find("<body>"));
  EXPECT_EQ(Count(page, "<head>"), 1u);
  EXPECT_EQ(Count(page, "<body>"), 1u);
  EXPECT_EQ(Count(page, "</body>"), 1u);
  EXPECT_EQ(page.substr(page.size() - 8), "</html>\n");
  for (const char* forbidden : {"<script", "src=", "href=", "@import", "url("})
    EXPECT_EQ(page.find(forbidden), std::string::npos) << forbidden;
}

TEST(HtmlKit, TableEscapesCellsAndListsNotes) {
  const std::string table = HtmlTable("t<1>", {"a", "b&c"}, {{"1", "<2>"}}, {"note 'x'"});
  EXPECT_NE(table.find("<caption>t&lt;1&gt;</caption>"), std::string::npos);
  EXPECT_NE(table.find("<th>b&amp;c</th>"), std::string::npos);
  EXPECT_NE(table.find("<td>&lt;2&gt;</td>"), std::string::npos);
  EXPECT_NE(table.find("<li>note &#39;x&#39;</li>"), std::string::npos);
  EXPECT_EQ(HtmlTable("", {"a"}, {}).find("<caption>"), std::string::npos);
}

// A key-value table carries the class whose values wrap anywhere (a long path without spaces
// stays within the page: the browser test renders one), and the stylesheet says so.
TEST(HtmlKit, FactsTableCellsWrapALongPath) {
  const std::string path = "/data/" + std::string(200, 'x') + "/geo.txt";
  const std::string table = HtmlFactsTable("", {{"Input <a>", path}});
  EXPECT_EQ(table.rfind("<table class=\"facts\">\n<tr><th>item</th><th>value</th></tr>\n", 0), 0u)
      << table;
  EXPECT_NE(table.find("<tr><td>Input &lt;a&gt;</td><td>" + path + "</td></tr>"), std::string::npos);
  EXPECT_EQ(table.find("<caption>"), std::string::npos);
  EXPECT_NE(HtmlFactsTable("t", {}).find("<caption>t</caption>"), std::string::npos);
  const std::string head = HtmlPageOpen("t", "h");
  EXPECT_NE(head.find("table.facts td+td{white-space:normal;overflow-wrap:anywhere}"),
            std::string::npos);
}

TEST(HtmlKit, GroupedHeaderNamesAQuantityOnceOverItsAxes) {
  const std::string table = HtmlTable("t", {"image", "X", "Y", "Z"}, {{"a", "1", "2", "3"}}, {},
                                      {{"", 1}, {"centre (m)", 3}});
  EXPECT_NE(table.find("<tr><th class=\"blank\"></th><th colspan=\"3\" class=\"group\">centre "
                       "(m)</th></tr>\n<tr><th>image</th><th>X</th>"),
            std::string::npos)
      << table;
  // Spans that do not cover the header: no group row.
  EXPECT_EQ(HtmlTable("t", {"a", "b"}, {}, {}, {{"x", 3}}).find("colspan"), std::string::npos);
}

TEST(HtmlKit, NiceSteps) {
  EXPECT_DOUBLE_EQ(NiceStep(10.0, 5), 2.0);
  EXPECT_DOUBLE_EQ(NiceStep(0.7, 5), 0.2);
  EXPECT_DOUBLE_EQ(NiceAtMost(7.0), 5.0);
  EXPECT_DOUBLE_EQ(NiceAtMost(0.3), 0.2);
  EXPECT_DOUBLE_EQ(NiceAtMost(0.0), 1.0);
  const PlotAxis axis = LinearPlotAxis(0.3, 9.2, true);
  EXPECT_DOUBLE_EQ(axis.lo, 0.0);
  EXPECT_DOUBLE_EQ(axis.hi, 10.0);
  EXPECT_EQ(axis.Ticks(), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  EXPECT_DOUBLE_EQ(axis.Fraction(5.0), 0.5);
}

TEST(HtmlKit, LinePlotCarriesItsAxisTitlesTicksAndLegend) {
  LinePlot plot;
  plot.title = "error vs noise";
  plot.x_label = "noise (px)";
  plot.y_label = "RMSE <m>";
  plot.series = {{"taylor", {0, 1, 2}, {0.0, 5.0, 10.0}}, {"ceres", {0, 1, 2}, {1.0, 2.0, 3.0}}};
  const std::string svg = RenderLinePlotSvg(plot);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_EQ(svg.substr(svg.size() - 6), "</svg>");
  EXPECT_NE(svg.find("aria-label=\"error vs noise\""), std::string::npos);
  EXPECT_NE(svg.find(">noise (px)</text>"), std::string::npos);
  EXPECT_NE(svg.find("rotate(-90"), std::string::npos);  // the y title along the axis
  EXPECT_NE(svg.find(">RMSE &lt;m&gt;</text>"), std::string::npos);
  // Ticks of both axes labelled: y 0..10 by 2, x 0..2 by 0.5.
  for (const char* tick : {">0</text>", ">2</text>", ">10</text>", ">0.5</text>", ">1.5</text>"})
    EXPECT_NE(svg.find(tick), std::string::npos) << tick;
  // Legend: each series named once in it (and in its markers' titles).
  EXPECT_NE(svg.find(">taylor</text>"), std::string::npos);
  EXPECT_NE(svg.find(">ceres</text>"), std::string::npos);
  EXPECT_EQ(Count(svg, "<polyline"), 2u);
}

TEST(HtmlKit, BarPlotAndHistogram) {
  BarPlot bars;
  bars.title = "time";
  bars.value_label = "microseconds";
  bars.labels = {"a", "b"};
  bars.values = {3.0, std::nan("")};
  const std::string bar_svg = RenderBarPlotSvg(bars);
  EXPECT_NE(bar_svg.find(">microseconds</text>"), std::string::npos);
  EXPECT_NE(bar_svg.find(">n/a</text>"), std::string::npos);
  EXPECT_EQ(Count(bar_svg, "<title>"), 1u);

  HistogramPlot histogram;
  histogram.title = "tie_marks";
  histogram.x_label = "residual (px)";
  for (int k = -50; k <= 50; ++k) histogram.values.push_back(0.01 * k);
  histogram.values.push_back(std::nan(""));
  const std::string svg = RenderHistogramSvg(histogram);
  EXPECT_NE(svg.find(">tie_marks (101)</text>"), std::string::npos);
  EXPECT_NE(svg.find(">residual (px)</text>"), std::string::npos);
  EXPECT_NE(svg.find(">count</text>"), std::string::npos);
  EXPECT_NE(svg.find(">-0.4</text>"), std::string::npos);  // a labelled tick of the x axis
  // 24 bins and the frame.
  EXPECT_EQ(Count(svg, "<rect x="), 24u + 1u);
  HistogramPlot empty;
  empty.title = "none";
  EXPECT_NE(RenderHistogramSvg(empty).find(">none (0)</text>"), std::string::npos);
}

TEST(HtmlKit, GlossaryListsEachTermWithItsMeaningEscaped) {
  EXPECT_EQ(HtmlGlossary({{"e^T C^-1 e", "below <3"}, {"w", "a test"}}),
            "<dl class=\"glossary\">\n<dt>e^T C^-1 e</dt><dd>below &lt;3</dd>\n<dt>w</dt><dd>a "
            "test</dd>\n</dl>\n");
}

TEST(HtmlKit, TickLabelsNeverTakeAnExponent) {
  EXPECT_EQ(TickLabel(0.0001), "0.0001");
  EXPECT_EQ(TickLabel(200000.0), "200000");
}

TEST(HtmlKit, HistogramOverAFixedRangeAndScatterPlot) {
  HistogramPlot redundancy;
  redundancy.title = "r";
  redundancy.x_label = "redundancy number";
  redundancy.values = {0.1, 0.5, 0.55, 0.9, 1.0};
  redundancy.lo = 0.0;
  redundancy.hi = 1.0;
  const std::string svg = RenderHistogramSvg(redundancy);
  // The x axis runs from 0 to 1, not symmetric about 0.
  EXPECT_NE(svg.find(">0</text>"), std::string::npos);
  EXPECT_NE(svg.find(">1</text>"), std::string::npos);
  EXPECT_EQ(svg.find(">-1</text>"), std::string::npos);
  EXPECT_NE(svg.find(">count</text>"), std::string::npos);
  EXPECT_EQ(Count(svg, "class=\"axis-label\""), 2u);
  // Marked as a histogram, its x ticks marked for the page test (all in [0, 1] here).
  EXPECT_NE(svg.find("class=\"plot histogram\""), std::string::npos);
  EXPECT_NE(svg.find("class=\"tick-x\">0</text>"), std::string::npos);
  EXPECT_NE(svg.find("class=\"tick-x\">1</text>"), std::string::npos);
  EXPECT_EQ(svg.find("class=\"tick-x\">-"), std::string::npos);
  // Without values: the axes and their titles still, and "no data".
  HistogramPlot empty = redundancy;
  empty.values = {std::nan("")};
  const std::string nothing = RenderHistogramSvg(empty);
  EXPECT_EQ(Count(nothing, "class=\"axis-label\""), 2u);
  EXPECT_NE(nothing.find(">count</text>"), std::string::npos);
  EXPECT_NE(nothing.find(">no data</text>"), std::string::npos);

  ScatterPlot scatter;
  scatter.title = "vertical errors";
  scatter.x_label = "point";
  scatter.y_label = "error Z (mm)";
  scatter.x = {1, 2, 3};
  scatter.y = {-4.0, 2.0, std::nan("")};
  scatter.labels = {"A", "B", "C"};
  const std::string points = RenderScatterPlotSvg(scatter);
  EXPECT_EQ(Count(points, "<title>"), 2u);  // the NaN is left out
  EXPECT_NE(points.find("<title>A: -4</title>"), std::string::npos);
  // A tooltip never reads 0.000003: below 0.01 it says so.
  scatter.y = {-4.0, 2e-6, 1.0};
  EXPECT_NE(RenderScatterPlotSvg(scatter).find("<title>B: &lt; 0.01</title>"), std::string::npos);
  EXPECT_NE(points.find(">error Z (mm)</text>"), std::string::npos);
  EXPECT_EQ(Count(points, "class=\"axis-label\""), 2u);
  EXPECT_NE(points.find("class=\"plot\""), std::string::npos);
  EXPECT_NE(points.find("stroke-dasharray"), std::string::npos);  // the zero line
}

TEST(HtmlKit, SmallMultiplesDrawOnePanelPerSeriesSideBySideOnSharedAxes) {
  LinePlot plot;
  plot.title = "RMSE vs noise";
  plot.x_label = "noise (px)";
  plot.y_label = "RMSE (m)";
  plot.series = {{"a", {0, 1, 2}, {0.1, 0.2, 0.3}}, {"b", {0, 1, 2}, {0.1, 0.4, 0.9}}};
  const std::string svg = RenderSmallMultiplesSvg(plot);
  // One <svg> across the A4 content width holding both panels.
  EXPECT_EQ(Count(svg, "<svg"), 1u);
  EXPECT_EQ(svg.substr(svg.size() - 6), "</svg>");
  EXPECT_NE(svg.find("width=\"700\""), std::string::npos);
  EXPECT_NE(svg.find("aria-label=\"RMSE vs noise\""), std::string::npos);
  EXPECT_NE(svg.find(">a</text>"), std::string::npos);  // the panels' titles
  EXPECT_NE(svg.find(">b</text>"), std::string::npos);
  // Each panel: its own series in colour, the other in grey behind; the axis titles once.
  EXPECT_EQ(Count(svg, "stroke=\"#cccccc\""), 2u);
  EXPECT_EQ(Count(svg, ">RMSE (m)</text>"), 1u);
  EXPECT_EQ(Count(svg, ">noise (px)</text>"), 1u);
  EXPECT_EQ(Count(svg, "class=\"axis-label\""), 2u);
  // Narrow panels take about 3 tick steps: x 0, 1, 2 in each panel; y (covering the larger
  // series) 0, 0.5, 1 labelled once, on the first panel.
  EXPECT_EQ(Count(svg, ">2</text>"), 2u);
  EXPECT_EQ(Count(svg, ">0.5</text>"), 1u);
  EXPECT_EQ(Count(svg, ">1</text>"), 3u);
}

TEST(HtmlKit, SmallMultiplesFitLongPanelTitlesToTheirPanels) {
  // Six panels of (700 - 62 - 6 - 5 x 18) / 6 = 90.3 px: a 20-character title (about 124 px in
  // bold 10 px) is fitted to 100.3 px, which ends 5 px right of the last panel, inside the 700;
  // a short one is left at its own width.
  LinePlot plot;
  plot.x_label = "noise (px)";
  plot.y_label = "RMSE (m)";
  for (const char* label : {"a", "b", "c", "d", "e", "ceres_autodiff/huber"})
    plot.series.push_back({label, {0, 1}, {0.1, 0.2}});
  const std::string svg = RenderSmallMultiplesSvg(plot);
  EXPECT_EQ(Count(svg, "lengthAdjust=\"spacingAndGlyphs\""), 1u);
  const size_t title = svg.find(">ceres_autodiff/huber</text>");
  ASSERT_NE(title, std::string::npos);
  const std::string element = svg.substr(svg.rfind("<text", title), title - svg.rfind("<text", title));
  std::smatch x, length;
  ASSERT_TRUE(std::regex_search(element, x, std::regex(R"re( x="([0-9.]+)")re")));
  ASSERT_TRUE(std::regex_search(element, length, std::regex(R"re(textLength="([0-9.]+)")re")));
  EXPECT_NEAR(std::stod(length[1]), 100.3, 0.1);
  EXPECT_LE(std::stod(x[1]) + std::stod(length[1]) / 2, 700.0 - 1.0);
}

TEST(HtmlKit, SectionedTableHasOneHeaderAndAHeadingRowPerSection) {
  const std::string table = HtmlSectionedTable(
      "every setting", {"solver", "RMSE"},
      {{"noise 0.5 px", {{"taylor", "0.1"}, {"ceres", "0.1"}}, {}},
       {"noise 1 <px>", {{"taylor", "0.2"}}, {"not solved: 1 x degenerate"}}},
      {"a note"});
  EXPECT_EQ(Count(table, "<table>"), 1u);
  EXPECT_EQ(Count(table, "<th>solver</th>"), 1u);
  EXPECT_NE(table.find("<caption>every setting</caption>"), std::string::npos);
  EXPECT_NE(table.find("<tr class=\"section\"><th colspan=\"2\">noise 1 &lt;px&gt;</th></tr>"),
            std::string::npos);
  EXPECT_LT(table.find("noise 0.5 px"), table.find("<td>ceres</td>"));
  EXPECT_NE(table.find("<tr class=\"note\"><td colspan=\"2\">not solved: 1 x degenerate</td></tr>"),
            std::string::npos);
  EXPECT_NE(table.find("<li>a note</li>"), std::string::npos);
}

}  // namespace PHOTOPOSE_UNITY_ID
}  // namespace photopose::cli
