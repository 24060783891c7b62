#include "reports/plots.h"

#include <cstdlib>
#include <fstream>
#include <stdexcept>

namespace pz::reports {
namespace {

std::string Quote(const std::string& s) {
  std::string r = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') r += '\\';
    r += c;
  }
  return r + "\"";
}

std::string ShellQuote(const std::string& s) {
  std::string r = "'";
  for (char c : s) r += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return r + "'";
}

}  // namespace

std::filesystem::path WritePlotScript(const std::filesystem::path& dir, const Plot& plot) {
  const auto path = dir / (plot.name + ".gp");
  std::ofstream gp(path);
  if (!gp) throw std::runtime_error("cannot write " + path.string());
  gp << "# Rendered by piezoid; re-render with: gnuplot " << plot.name << ".gp\n"
     << "set terminal pngcairo size 1000,620 noenhanced font 'sans,11'\n"
     << "set output " << Quote(plot.name + ".png") << "\n"
     << "set datafile separator ','\n"
     << "set key outside top center horizontal\n"
     << "set grid\n"
     << "set title " << Quote(plot.title) << "\n"
     << "set xlabel " << Quote(plot.xlabel) << "\n"
     << "set ylabel " << Quote(plot.ylabel) << "\n";
  if (plot.logscale_y) gp << "set logscale y\n";
  if (!plot.xrange.empty()) gp << "set xrange " << plot.xrange << "\n";
  if (!plot.yrange.empty()) gp << "set yrange " << plot.yrange << "\n";
  gp << "plot ";
  for (size_t i = 0; i < plot.series.size(); ++i) {
    const auto& s = plot.series[i];
    gp << (i ? ", \\\n     " : "") << Quote(s.data_file) << " using " << s.x_column << ":"
       << s.y_column << " skip 1 with " << s.style << " lw 1.5 title " << Quote(s.title);
  }
  gp << "\n";
  if (!gp) throw std::runtime_error("cannot write " + path.string());
  return path;
}

bool GnuplotAvailable() { return std::system("gnuplot --version >/dev/null 2>&1") == 0; }

int RenderPlots(const std::filesystem::path& dir, const std::vector<std::filesystem::path>& scripts,
                std::vector<std::string>* errors) {
  int ok = 0;
  for (const auto& s : scripts) {
    const std::string cmd = "cd " + ShellQuote(dir.string()) + " && gnuplot " +
                            ShellQuote(s.filename().string()) + " 2>&1";
    if (std::system((cmd + " >/dev/null").c_str()) == 0) {
      ++ok;
    } else if (errors) {
      errors->push_back("gnuplot failed on " + s.string() + " (run: " + cmd + ")");
    }
  }
  return ok;
}

}  // namespace pz::reports
