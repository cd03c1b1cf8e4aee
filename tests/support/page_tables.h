#pragma once
// The tables of a report page (tools/report/html_kit.h HtmlTable), for tests that read a page.
#include <cmath>
#include <regex>
#include <string>
#include <vector>

namespace photopose::testing {

// The <table> of `html` whose caption starts with `caption` (as escaped on the page), or "". Its
// notes follow it, outside.
inline std::string TableWithCaption(const std::string& html, const std::string& caption) {
  const size_t at = html.find("<caption>" + caption);
  if (at == std::string::npos) return "";
  const size_t open = html.rfind("<table", at);
  return html.substr(open, html.find("</table>", at) + 8 - open);
}

// The numbers of the row of `table` that starts with the cells `first_cells` ("<td>check</td>"),
// after them; "n/a" as NaN; empty when there is no such row.
inline std::vector<double> RowNumbers(const std::string& table, const std::string& first_cells) {
  const size_t start = table.find("<tr>" + first_cells);
  if (start == std::string::npos) return {};
  const size_t from = start + 4 + first_cells.size();
  const std::string rest = table.substr(from, table.find("</tr>", from) - from);
  std::vector<double> numbers;
  const std::regex cell("<td>([^<]*)</td>");
  for (auto it = std::sregex_iterator(rest.begin(), rest.end(), cell); it != std::sregex_iterator();
       ++it)
    numbers.push_back((*it)[1] == "n/a" ? std::nan("") : std::stod((*it)[1]));
  return numbers;
}

}  // namespace photopose::testing
