// `piezoid export`: the generated C header, compiled by the system C compiler (cc) into a small
// program, predicts the seven parameters over a grid of (V, f) — inside and outside the training
// box, through every transfer function's kinks — exactly as model::Network::Predict does (checked
// to 1e-12 relative; bit-identical on x86-64).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "controller/export_c.h"
#include "io/network_io.h"
#include "model/chromosome.h"
#include "tests/testing/shell.h"

namespace pz::client {
namespace {

namespace fs = std::filesystem;

using pz::testing::BuildDir;
using pz::testing::Shell;

bool HaveCc() { return Shell("command -v cc >/dev/null 2>&1") == 0; }

/// Random valid networks (seeded), enough of them that every transfer function appears in every
/// layer, on the nominal set's training box.
std::vector<io::SavedNetwork> Networks() {
  model::InputNormalization norm{375, 750, 0.25, 1};
  std::mt19937_64 rng(2024);
  std::vector<io::SavedNetwork> out;
  std::set<int> in_tf, hidden_tf, out_tf;
  for (int i = 0; i < 200 && (out.size() < 12 || in_tf.size() < 8 || hidden_tf.size() < 8 ||
                              out_tf.size() < 8);
       ++i) {
    std::vector<uint8_t> bits(model::kChromosomeBits);
    for (auto& b : bits) b = rng() & 1;
    if (!model::ValidateChromosome(bits).ok()) continue;
    io::SavedNetwork s;
    s.network = model::DecodeChromosome(
        bits, norm, i % 2 ? model::ParameterRanges::PaperTable3() : model::ParameterRanges{});
    s.chromosome = bits;
    s.provenance.job_id = "test";
    s.provenance.seed = 2024;
    for (auto t : s.network.input_tf) in_tf.insert(static_cast<int>(t));
    for (auto t : s.network.hidden_tf) hidden_tf.insert(static_cast<int>(t));
    for (auto t : s.network.output_tf) out_tf.insert(static_cast<int>(t));
    out.push_back(std::move(s));
  }
  EXPECT_EQ(in_tf.size(), 8u);
  EXPECT_EQ(hidden_tf.size(), 8u);
  EXPECT_EQ(out_tf.size(), 8u);
  return out;
}

TEST(ExportC, NamesMustBeCIdentifiers) {
  EXPECT_TRUE(IsCIdentifier("piezoid_predict"));
  EXPECT_TRUE(IsCIdentifier("_fin2"));
  EXPECT_FALSE(IsCIdentifier("2fin"));
  EXPECT_FALSE(IsCIdentifier("fin-model"));
  EXPECT_FALSE(IsCIdentifier(""));
  std::string h;
  const auto nets = Networks();
  EXPECT_EQ(controller::NetworkToCHeader(nets[0], "my fn", &h).code(),
            StatusCode::kInvalidArgument);
  io::SavedNetwork bad = nets[0];
  bad.network.w1(0, 0) = std::nan("");
  EXPECT_EQ(controller::NetworkToCHeader(bad, "f", &h).code(), StatusCode::kInvalidArgument);
}

TEST(ExportC, CompiledHeaderPredictsLikeTheLibrary) {
  if (!HaveCc()) GTEST_SKIP() << "no C compiler 'cc' on the PATH";
  const fs::path dir = fs::temp_directory_path() / ("pz-export-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto nets = Networks();

  // One header through the CLI (the command users run), the others through the library.
  ASSERT_TRUE(io::SaveNetwork(nets[0], (dir / "net0.pb").string()).ok());
  const std::string cli = "'" + (BuildDir() / "client" / "piezoid").string() + "' export '" +
                          (dir / "net0.pb").string() + "' --out '" + (dir / "net0.h").string() +
                          "' --name net0 2>'" + (dir / "cli.err").string() + "'";
  ASSERT_EQ(Shell(cli), 0) << cli;
  {  // The folder that identify / fetch write (network.pb, networks/best-1.pb) gives the same
     // header.
    const std::string piezoid = "'" + (BuildDir() / "client" / "piezoid").string() + "' export '";
    fs::create_directories(dir / "fetched" / "networks");
    fs::copy_file(dir / "net0.pb", dir / "fetched" / "networks" / "best-1.pb");
    ASSERT_EQ(Shell(piezoid + (dir / "fetched").string() + "' --out '" +
                    (dir / "fetched.h").string() + "' --name net0"),
              0);
    fs::copy_file(dir / "net0.pb", dir / "fetched" / "network.pb");
    ASSERT_EQ(Shell(piezoid + (dir / "fetched").string() + "' --out '" +
                    (dir / "fetched2.h").string() + "' --name net0"),
              0);
    const auto text = [](const fs::path& p) {
      std::ostringstream os;
      os << std::ifstream(p).rdbuf();
      return os.str();
    };
    EXPECT_EQ(text(dir / "fetched.h"), text(dir / "net0.h"));
    EXPECT_EQ(text(dir / "fetched2.h"), text(dir / "net0.h"));
    fs::create_directories(dir / "empty");
    EXPECT_NE(Shell(piezoid + (dir / "empty").string() + "' --out '" + (dir / "e.h").string() +
                    "' 2>'" + (dir / "empty.err").string() + "'"),
              0);
    EXPECT_NE(
        text(dir / "empty.err").find("a folder without fit.json, network.pb or networks/best-1.pb"),
        std::string::npos)
        << text(dir / "empty.err");
  }
  for (size_t i = 1; i < nets.size(); ++i) {
    std::string h;
    ASSERT_TRUE(controller::NetworkToCHeader(nets[i], "net" + std::to_string(i), &h).ok());
    std::ofstream(dir / ("net" + std::to_string(i) + ".h")) << h;
  }

  const std::vector<double> vs = {0, 100, 375, 400.5, 500, 562.5, 620.125, 750, 900, 1500};
  const std::vector<double> fs_ = {0.01, 0.25, 0.3, 0.5, 0.625, 0.77, 1, 1.5, 3};
  std::ostringstream prog;
  prog << "#include <stdio.h>\n";
  for (size_t i = 0; i < nets.size(); ++i) prog << "#include \"net" << i << ".h\"\n";
  prog << "int main(void) {\n  static const double vs[] = {";
  for (size_t i = 0; i < vs.size(); ++i) prog << (i ? ", " : "") << vs[i];
  prog << "};\n  static const double fs[] = {";
  for (size_t i = 0; i < fs_.size(); ++i) prog << (i ? ", " : "") << fs_[i];
  prog << "};\n  double p[7];\n  int a, b, k;\n";
  for (size_t i = 0; i < nets.size(); ++i)
    prog << "  for (a = 0; a < " << vs.size() << "; ++a) for (b = 0; b < " << fs_.size()
         << "; ++b) {\n"
         << "    net" << i << "(vs[a], fs[b], p);\n"
         << "    for (k = 0; k < 7; ++k) printf(\"%a\\n\", p[k]);\n  }\n";
  prog << "  return 0;\n}\n";
  std::ofstream(dir / "prog.c") << prog.str();
  const std::string compile =
      "cd '" + dir.string() +
      "' && cc -std=c99 -O2 -Wall -Wextra -Werror -pedantic -o prog prog.c -lm 2>cc.err";
  ASSERT_EQ(Shell(compile), 0) << std::ifstream(dir / "cc.err").rdbuf();
  ASSERT_EQ(Shell("cd '" + dir.string() + "' && ./prog > out.txt"), 0);

  std::ifstream in(dir / "out.txt");
  std::string line;
  int exact = 0, total = 0;
  for (size_t i = 0; i < nets.size(); ++i) {
    for (double v : vs) {
      for (double f : fs_) {
        const auto want = nets[i].network.Predict(v, f).ToArray();
        for (int k = 0; k < 7; ++k) {
          ASSERT_TRUE(std::getline(in, line)) << "output ended early";
          const double got = std::strtod(line.c_str(), nullptr);
          EXPECT_LE(std::abs(got - want[k]), 1e-12 * std::max(1.0, std::abs(want[k])))
              << "network " << i << " (" << nets[i].network.Describe() << ") V " << v << " f " << f
              << " output " << model::OutputName(k) << ": C " << got << " vs library " << want[k];
          exact += got == want[k];
          ++total;
        }
      }
    }
  }
  EXPECT_FALSE(std::getline(in, line)) << "extra output";
  EXPECT_EQ(total, static_cast<int>(nets.size() * vs.size() * fs_.size() * 7));
  RecordProperty("exact", exact);
  RecordProperty("total", total);
  std::printf("%d of %d predictions bit-identical to the library\n", exact, total);
  if (!::testing::Test::HasFailure()) fs::remove_all(dir);
}

}  // namespace
}  // namespace pz::client
