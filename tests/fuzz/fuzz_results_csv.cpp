// results.csv files (`nbv experiment --merge`): read or refused with InvalidArgument; rows read
// write back as text that reads back to the same rows and writes the same text again, and
// make a Table 1.
#include "fuzz_input_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/experiment.hpp"

#include <cmath>
#include <fstream>
#include <tuple>

namespace {

bool same(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

bool sameRow(const nbv::planner::ExperimentRow& a, const nbv::planner::ExperimentRow& b) {
  return std::tie(a.model, a.metric, a.trial, a.iteration, a.view, a.ties, a.rays) ==
             std::tie(b.model, b.metric, b.trial, b.iteration, b.view, b.ties, b.rays) &&
         same(a.coverage, b.coverage) && same(a.entropy_bits, b.entropy_bits) &&
         same(a.max_entropy_bits, b.max_entropy_bits) && same(a.seconds_render, b.seconds_render) &&
         same(a.seconds_integrate, b.seconds_integrate) && same(a.seconds_ig, b.seconds_ig) && same(a.gap, b.gap);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = nbv::fuzz::writeInput(data, size, ".csv");
  std::vector<nbv::planner::ExperimentRow> rows;
  try {
    rows = nbv::planner::readResultsCsv(path);
  } catch (const nbv::InvalidArgument&) {
    return 0;
  }
  nbv::planner::sortRows(rows);
  const std::string text = nbv::planner::resultsCsv(rows);
  const auto again_path = nbv::fuzz::inputPath(".again.csv");
  std::ofstream(again_path, std::ios::binary | std::ios::trunc) << text;
  const std::vector<nbv::planner::ExperimentRow> again = nbv::planner::readResultsCsv(again_path);
  nbv::fuzz::check(again.size() == rows.size(), "as many rows read back as written");
  for (std::size_t i = 0; i < rows.size(); ++i) nbv::fuzz::check(sameRow(rows[i], again[i]), "every field reads back");
  nbv::fuzz::check(nbv::planner::resultsCsv(again) == text, "the same text written again");
  nbv::fuzz::check(!nbv::planner::table1Markdown(rows).empty(), "a table");
  return 0;
}
