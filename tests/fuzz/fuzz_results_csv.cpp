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
bool same(std::uint64_t a, std::uint64_t b) { return a == b; }

/// Every field of the row: the run's keys, then each field of the record's table (NaN as NaN).
bool sameRow(const nbv::planner::ExperimentRow& a, const nbv::planner::ExperimentRow& b) {
  bool equal = std::tie(a.model, a.metric, a.trial) == std::tie(b.model, b.metric, b.trial);
#define NBV_SAME_FIELD(name, type, kind, help) equal = equal && same(a.name, b.name);
  NBV_ITERATION_FIELDS(NBV_SAME_FIELD)
#undef NBV_SAME_FIELD
  return equal;
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
