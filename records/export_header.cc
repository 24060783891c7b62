#include "records/export_header.h"

#include <cctype>
#include <cstdint>
#include <cstdio>
#include <map>
#include <sstream>
#include <string_view>

#include "io/csv.h"
#include "model/c_text.h"

namespace pz::records {
namespace kernel_text {
extern const std::string_view kCommon, kEffects, kStackModels, kPlayOperators, kBwOscillator, kFinModal, kBimorphFin, kChain;
}  // namespace kernel_text

namespace {

// The PZK_* name of a block kind, read from the kernels' own enum (records/kernels/common.h, the
// one list of the ids that the families' and effects' registrations give): `NAME` or `NAME = N`,
// comma-separated, comments skipped.
std::string KindMacro(int kind) {
  static const std::map<int, std::string> names = [] {
    std::map<int, std::string> m;
    const std::string_view text = kernel_text::kCommon;
    const size_t at = text.find("enum {") + 6;
    std::string body(text.substr(at, text.find("};", at) - at));
    for (size_t c = body.find("/*"); c != std::string::npos; c = body.find("/*"))
      body.erase(c, body.find("*/", c) + 2 - c);
    std::istringstream items(body);
    int next = 0;
    for (std::string item; std::getline(items, item, ',');) {
      std::istringstream is(item);
      std::string name, eq;
      if (!(is >> name)) continue;
      if (is >> eq && eq == "=") is >> next;
      m[next++] = name;
    }
    return m;
  }();
  const auto it = names.find(kind);
  return it == names.end() ? "0" : it->second;
}

void Array(std::ostream& os, const std::string& name, const double* v, int n) {
  os << "static const double " << name << "[" << std::max(n, 1) << "] = {";
  for (int i = 0; i < n; ++i) os << (i ? ", " : "") << (i % 4 == 0 ? "\n  " : "") << CHexLiteral(v[i]);
  if (n == 0) os << "0";
  os << "};\n";
}

}  // namespace

std::string KernelSource() {
  std::string s;
  for (std::string_view part : {kernel_text::kCommon, kernel_text::kEffects, kernel_text::kStackModels,
                                kernel_text::kPlayOperators, kernel_text::kBwOscillator, kernel_text::kFinModal, kernel_text::kBimorphFin,
                                kernel_text::kChain}) {
    s.append(part);
  }
  return s;
}

std::string KernelGuard() {
  // FNV-1a (64 bit) of the kernels' text: headers exported from the same kernels share them; a
  // header from other kernels (another piezoid) has its own guard, so two of them in one
  // translation unit fail to compile (the functions are defined twice) instead of one silently
  // using the other's block layout.
  uint64_t h = 14695981039346656037ULL;
  for (unsigned char c : KernelSource()) h = (h ^ c) * 1099511628211ULL;
  char guard[40];
  std::snprintf(guard, sizeof guard, "PZK_KERNELS_%016llX", static_cast<unsigned long long>(h));
  return guard;
}

std::string FinModalSource() { return std::string(kernel_text::kFinModal); }

std::string ExportHeader(const Stepper& st, const std::string& name, const std::string& comment) {
  if (!IsCIdentifier(name)) {
    throw InputError("--name '" + name + "': must be a C identifier ([A-Za-z_][A-Za-z0-9_]*, at most 63 characters)");
  }
  const ModelSpec& m = st.spec();
  const std::string N = CUpper(name);
  const auto& blocks = st.blocks();
  const int nb = static_cast<int>(blocks.size());
  std::ostringstream os;
  std::string safe = comment;
  for (size_t i = 0; i + 1 < safe.size(); ++i)
    if (safe[i] == '*' && safe[i + 1] == '/') safe[i] = '_';
  os << "/* " << name << ".h: " << safe << "\n"
     << " *\n"
     << " * Written by `piezoid export` (issue 23). Self-contained C99: only <math.h>, no allocation, no\n"
     << " * mutable global. Drive in " << m.drive_unit << ", response in " << m.response_unit << ", one call per sample of\n"
     << " * " << io::FormatNumber(m.dt) << " s (the rate the model was identified at).\n"
     << " *\n"
     << " *   " << name << "_state s;\n"
     << " *   " << name << "_init(&s, u0);                 at rest under the drive u0 (returns the response)\n"
     << " *   y = " << name << "_step(&s, u);              forward model: the response to drive u\n"
     << " *   u = " << name << "_inverse_step(&s, y_des);  compensator: the drive for the desired response\n"
     << " *\n"
     << " * A state is used either forward or as a compensator after init, not both. Drives are clipped to\n"
     << " * [s.ctl.u_lo, s.ctl.u_hi] (init sets " << N << "_U_MIN, " << N << "_U_MAX: the training records'\n"
     << " * drive range; change them after init for another amplifier); s.ctl.saturated counts clipped\n"
     << " * samples, s.ctl.max_clip the largest clipping (drive units forward, response units inverse).\n"
     << " * The inverse solves the one-step map by a bracketed search (exact for the monotone families). Give\n"
     << " * it the reference " << N << "_PREVIEW_SAMPLES ahead (preview) where the reference is known in advance:\n"
     << " * a delay of n + s samples (" << N << "_DELAY_S) cannot be undone by a causal step; the compensator\n"
     << " * reads n samples ahead and solves the fraction s in its one-step map for s <= 1/2; for s > 1/2 it\n"
     << " * reads L more and undoes s backwards over them (records/kernels/effects.h: the delay)."
     << (st.inverse_plan_samples() > 1
             ? " This compensator plans two samples (the bimorph fin, or a rate-dependence lag over a\n"
               " * quarter sample: records/kernels/chain.h pzk_chain_inverse_fin): one sample of the preview."
             : std::string())
     << " Model: " << m.Model()->Describe()
     << (m.Model()->family().initial_state() != model::InitialState::kCentred
             ? std::string(", at rest in the ") + model::InitialStateName(m.Model()->family().initial_state()) +
                   " state (docs/records.md)"
             : std::string())
     << ". */\n"
     << "#ifndef " << N << "_H_\n#define " << N << "_H_\n\n#include <math.h>\n\n"
     << "#ifndef " << KernelGuard() << "\n#define " << KernelGuard() << "\n"
     << KernelSource() << "#endif /* " << KernelGuard() << " */\n\n";
  double delay = 0;
  for (int i = 0; i < nb; ++i)
    if (blocks[i].kind == pzk::PZK_DELAY) delay = blocks[i].p[0];
  os << "#define " << N << "_U_MIN " << CHexLiteral(m.drive_min) << " /* " << io::FormatNumber(m.drive_min) << " " << m.drive_unit
     << " */\n"
     << "#define " << N << "_U_MAX " << CHexLiteral(m.drive_max) << " /* " << io::FormatNumber(m.drive_max) << " " << m.drive_unit
     << " */\n"
     << "#define " << N << "_DT_S " << CHexLiteral(m.dt) << "\n"
     << "#define " << N << "_DELAY_S " << CHexLiteral(delay) << "\n"
     << "#define " << N << "_PREVIEW_SAMPLES " << st.preview_samples() << "\n"
     << "#define " << N << "_PRIME_SAMPLES " << st.delay_horizon() << "\n"
     << "#define " << N << "_BLOCKS " << nb << "\n\n";
  for (int i = 0; i < nb; ++i) {
    const auto& p = st.block_params(static_cast<size_t>(i));
    Array(os, name + "_p" + std::to_string(i) + "_", p.data(), static_cast<int>(p.size()));
    if (blocks[i].nw > 0) Array(os, name + "_w" + std::to_string(i) + "_", blocks[i].w, blocks[i].nw);
  }
  os << "static const pzk_block " << name << "_blocks_[" << nb << "] = {\n";
  for (int i = 0; i < nb; ++i) {
    const auto& b = blocks[i];
    const std::string w = b.nw > 0 ? name + "_w" + std::to_string(i) + "_" : "0";
    os << "  {" << KindMacro(b.kind) << ", " << b.n << ", " << b.m << ", " << CHexLiteral(b.dt) << ", " << CHexLiteral(b.u_min) << ", "
       << CHexLiteral(b.u_max) << ", " << CHexLiteral(b.u_half) << ", " << CHexLiteral(b.y_half) << ",\n   " << name << "_p" << i << "_, "
       << b.np << ", " << w << ", " << b.nw << ", " << b.c_off << ", " << b.d_off << ", "
       << (b.init == pzk::PZK_DESCENDED  ? "PZK_DESCENDED"
           : b.init == pzk::PZK_ASCENDED ? "PZK_ASCENDED"
           : b.init == pzk::PZK_AUTO     ? "PZK_AUTO"
                                         : "PZK_CENTRED")
       << "}"
       << (i + 1 < nb ? "," : "")
       << "\n";
  }
  os << "};\n\n";
  const int nc = std::max(st.constants(), 1), nd = std::max(st.dynamic(), 1);
  os << "typedef struct {\n  double c[" << nc << "]; /* constants derived at init */\n  double d[" << nd
     << "]; /* dynamic state */\n  double t[" << nd << "]; /* the inverse's trial state */\n"
     << "  pzk_ctl ctl;  /* limits, last drive and output, saturation counter */\n} " << name << "_state;\n\n"
     << "static inline double " << name << "_init(" << name << "_state *s, double u0) {\n"
     << "  s->ctl.u_lo = " << N << "_U_MIN;\n  s->ctl.u_hi = " << N << "_U_MAX;\n"
     << "  return pzk_chain_init(" << name << "_blocks_, " << N << "_BLOCKS, s->c, s->d, &s->ctl, u0);\n}\n\n"
     << "static inline double " << name << "_step(" << name << "_state *s, double u) {\n"
     << "  return pzk_chain_step(" << name << "_blocks_, " << N << "_BLOCKS, s->c, s->d, &s->ctl, u);\n}\n\n"
     << "static inline double " << name << "_inverse_step(" << name << "_state *s, double y_desired) {\n"
     << "  return pzk_chain_inverse(" << name << "_blocks_, " << N << "_BLOCKS, s->c, s->d, s->t, &s->ctl, y_desired);\n}\n\n"
     << "/* " << N << "_PRIME_SAMPLES > 0 (a delay's fraction over a half): after init, the references of the\n"
     << " * " << N << "_PRIME_SAMPLES samples before the first inverse step's, in order; returns -1 when none is wanted. */\n"
     << "static inline int " << name << "_inverse_prime(" << name << "_state *s, double y_desired) {\n"
     << "  return pzk_chain_inverse_prime(" << name << "_blocks_, " << N << "_BLOCKS, s->c, s->d, s->t, &s->ctl, y_desired);\n}\n\n"
     << "#endif /* " << N << "_H_ */\n";
  return os.str();
}

}  // namespace pz::records
