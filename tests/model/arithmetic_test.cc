// The measured arithmetic (model/arithmetic.h): the fingerprint is a function of what this process
// computes, the same on every call and on every thread; a profile names the build and the parts;
// two profiles are told apart by the parts that differ, named with both values.
#include <gtest/gtest.h>

#include <iostream>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "model/arithmetic.h"

namespace pz::model {
namespace {

TEST(Arithmetic, TheFingerprintMeasuresEveryPartOnceAndTheSameOnEveryThread) {
  for (const auto& [key, value] : ArithmeticReport()) std::cout << key << ": " << value << "\n";
  const std::vector<ArithmeticPart>& parts = MeasuredArithmetic();
  std::set<std::string> names;
  for (const ArithmeticPart& p : parts) {
    names.insert(p.name);
    EXPECT_NE(p.digest, 0u) << p.name;
    EXPECT_FALSE(p.what.empty()) << p.name;
  }
  EXPECT_EQ(names, (std::set<std::string>{"libm", "eigen", "dense", "fin", "cvode", "tansig"}));
  const std::string fp = ArithmeticFingerprint();
  std::string other;
  std::thread t([&other] { other = ArithmeticFingerprint(); });
  t.join();
  EXPECT_EQ(other, fp);
  EXPECT_EQ(ArithmeticProfile().find(fp), ArithmeticProfile().size() - fp.size());
  EXPECT_EQ(ArithmeticDigest().size(), 16u);
}

TEST(Arithmetic, TwoProfilesDifferByTheirNamedParts) {
  const std::string ours = ArithmeticProfile();
  EXPECT_EQ(ArithmeticDifference(ours, ours), "");
  // Another machine: its libm part differs.
  std::string theirs = ours;
  const size_t at = theirs.find("libm=") + 5;
  theirs[at] = theirs[at] == '0' ? '1' : '0';
  const std::string d = ArithmeticDifference(ours, theirs);
  EXPECT_EQ(d.find("libm ("), 0u) << d;
  EXPECT_NE(d.find(ours.substr(at, 16) + " here, " + theirs.substr(at, 16) + " there"),
            std::string::npos)
      << d;
  EXPECT_EQ(d.find("fin"), std::string::npos) << "only what differs: " << d;
  // Another build, and a profile of an older format.
  EXPECT_EQ(ArithmeticDifference(ours, "piezoid 0.0.1; x86-64; glibc 2.19").find("the build ("),
            0u);
  EXPECT_EQ(ArithmeticDifference(ours, "").find("the build ("), 0u);
}

}  // namespace
}  // namespace pz::model
