// Figures through gnuplot: each figure is a gnuplot script written next to its data, then rendered
// to PNG (pngcairo). Without gnuplot on the PATH the scripts stay, and a warning says how to
// render.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace pz::reports {

struct PlotSeries {
  std::string data_file;  ///< CSV with a header row, relative to the script's folder
  int x_column = 1;       ///< 1-based
  int y_column = 2;       ///< 1-based
  std::string title;
  std::string style = "lines";  ///< gnuplot style: lines, points, linespoints
};

struct Plot {
  std::string name;  ///< file stem: <name>.gp and <name>.png
  std::string title;
  std::string xlabel;
  std::string ylabel;
  bool logscale_y = false;
  std::vector<PlotSeries> series;
  std::string xrange{};  ///< gnuplot's "[lo:hi]"; empty: automatic
  std::string yrange{};  ///< as xrange, for y
};

/// Writes dir/<name>.gp. Returns the script path.
std::filesystem::path WritePlotScript(const std::filesystem::path& dir, const Plot& plot);

/// True if `gnuplot` can be run.
bool GnuplotAvailable();

/// Renders every script (in `dir`, with `dir` as working folder). Returns the number rendered;
/// appends a line per failure to `errors`.
int RenderPlots(const std::filesystem::path& dir, const std::vector<std::filesystem::path>& scripts,
                std::vector<std::string>* errors);

}  // namespace pz::reports
