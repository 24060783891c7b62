#include "controller/export_header.h"

#include <cctype>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string_view>

#include "io/csv.h"
#include "model/c_text.h"
#include "model/kernels/kernel_text.h"

namespace pz::controller {

namespace {

void Array(std::ostream& os, const std::string& name, const double* v, int n) {
  os << "static const double " << name << "[" << std::max(n, 1) << "] = {";
  for (int i = 0; i < n; ++i)
    os << (i ? ", " : "") << (i % 4 == 0 ? "\n  " : "") << CHexLiteral(v[i]);
  if (n == 0) os << "0";
  os << "};\n";
}

/// The header's comment (how to call it, the model) and the kernels' C source.
void WriteBanner(std::ostream& os, const records::Stepper& st, const std::string& name,
                 const std::string& safe) {
  const records::ModelSpec& m = st.spec();
  const std::string N = CUpper(name);
  os << "/* " << name << ".h: " << safe << "\n"
     << " *\n"
     << " * Written by `piezoid export` (issue 23). Self-contained C99: only <math.h>, no "
        "allocation, no\n"
     << " * mutable global. Drive in " << m.drive_unit << ", response in " << m.response_unit
     << ", one call per sample of\n"
     << " * " << io::FormatNumber(m.dt) << " s (the rate the model was identified at).\n"
     << " *\n"
     << " *   " << name << "_state s;\n"
     << " *   " << name
     << "_init(&s, u0);                 at rest under the drive u0 (returns the response)\n"
     << " *   y = " << name << "_step(&s, u);              forward model: the response to drive u\n"
     << " *   u = " << name
     << "_inverse_step(&s, y_des);  compensator: the drive for the desired response\n"
     << " *\n"
     << " * A state is used either forward or as a compensator after init, not both. Drives are "
        "clipped to\n"
     << " * [s.ctl.u_lo, s.ctl.u_hi] (init sets " << N << "_U_MIN, " << N
     << "_U_MAX: the training records'\n"
     << " * drive range; change them after init for another amplifier); s.ctl.saturated counts "
        "clipped\n"
     << " * samples, s.ctl.max_clip the largest clipping (drive units forward, response units "
        "inverse).\n"
     << " * The inverse solves the one-step map by a bracketed search (exact for the monotone "
        "families). Give\n"
     << " * it the reference " << N
     << "_PREVIEW_SAMPLES ahead (preview) where the reference is known in advance:\n"
     << " * a delay of n + s samples (" << N
     << "_DELAY_S) cannot be undone by a causal step; the compensator\n"
     << " * reads n samples ahead and solves the fraction s in its one-step map for s <= 1/2; for "
        "s > 1/2 it\n"
     << " * reads L more and undoes s backwards over them (model/kernels/effects.h: the delay)."
     << (st.inverse_plan_samples() > 1 ? " This compensator plans two samples (the bimorph fin, or "
                                         "a rate-dependence lag over a\n"
                                         " * quarter sample: model/kernels/chain.h "
                                         "pzk_chain_inverse_fin): one sample of the preview."
                                       : std::string())
     << " Model: " << m.Model()->Describe()
     << (m.Model()->family().initial_state() != model::InitialState::kCentred
             ? std::string(", at rest in the ") +
                   model::InitialStateName(m.Model()->family().initial_state()) +
                   " state (docs/records.md)"
             : std::string())
     << ". */\n"
     << "#ifndef " << N << "_H_\n#define " << N << "_H_\n\n#include <math.h>\n\n"
     << "#ifndef " << pzk::KernelGuard() << "\n#define " << pzk::KernelGuard() << "\n"
     << pzk::KernelSource() << "#endif /* " << pzk::KernelGuard() << " */\n\n";
}

/// Every block's parameter and weight arrays and the block table.
void WriteBlocks(std::ostream& os, const records::Stepper& st, const std::string& name) {
  const auto& blocks = st.blocks();
  const int nb = static_cast<int>(blocks.size());
  for (int i = 0; i < nb; ++i) {
    const auto& p = st.block_params(static_cast<size_t>(i));
    Array(os, name + "_p" + std::to_string(i) + "_", p.data(), static_cast<int>(p.size()));
    if (blocks[i].nw > 0)
      Array(os, name + "_w" + std::to_string(i) + "_", blocks[i].w, blocks[i].nw);
  }
  os << "static const pzk_block " << name << "_blocks_[" << nb << "] = {\n";
  for (int i = 0; i < nb; ++i) {
    const auto& b = blocks[i];
    const std::string w = b.nw > 0 ? name + "_w" + std::to_string(i) + "_" : "0";
    os << "  {" << pzk::KindName(b.kind) << ", " << b.n << ", " << b.m << ", " << CHexLiteral(b.dt)
       << ", " << CHexLiteral(b.u_min) << ", " << CHexLiteral(b.u_max) << ", "
       << CHexLiteral(b.u_half) << ", " << CHexLiteral(b.y_half) << ",\n   " << name << "_p" << i
       << "_, " << b.np << ", " << w << ", " << b.nw << ", " << b.c_off << ", " << b.d_off << ", "
       << (b.init == pzk::PZK_DESCENDED  ? "PZK_DESCENDED"
           : b.init == pzk::PZK_ASCENDED ? "PZK_ASCENDED"
           : b.init == pzk::PZK_AUTO     ? "PZK_AUTO"
                                         : "PZK_CENTRED")
       << "}" << (i + 1 < nb ? "," : "") << "\n";
  }
  os << "};\n\n";
}

/// The state type and the init, step, inverse step and inverse prime functions.
void WriteFunctions(std::ostream& os, const records::Stepper& st, const std::string& name) {
  const std::string N = CUpper(name);
  const int nc = std::max(st.constants(), 1), nd = std::max(st.dynamic(), 1);
  os << "typedef struct {\n  double c[" << nc << "]; /* constants derived at init */\n  double d["
     << nd << "]; /* dynamic state */\n  double t[" << nd << "]; /* the inverse's trial state */\n"
     << "  pzk_ctl ctl;  /* limits, last drive and output, saturation counter */\n} " << name
     << "_state;\n\n"
     << "static inline double " << name << "_init(" << name << "_state *s, double u0) {\n"
     << "  s->ctl.u_lo = " << N << "_U_MIN;\n  s->ctl.u_hi = " << N << "_U_MAX;\n"
     << "  return pzk_chain_init(" << name << "_blocks_, " << N
     << "_BLOCKS, s->c, s->d, &s->ctl, u0);\n}\n\n"
     << "static inline double " << name << "_step(" << name << "_state *s, double u) {\n"
     << "  return pzk_chain_step(" << name << "_blocks_, " << N
     << "_BLOCKS, s->c, s->d, &s->ctl, u);\n}\n\n"
     << "static inline double " << name << "_inverse_step(" << name
     << "_state *s, double y_desired) {\n"
     << "  return pzk_chain_inverse(" << name << "_blocks_, " << N
     << "_BLOCKS, s->c, s->d, s->t, &s->ctl, y_desired);\n}\n\n"
     << "/* " << N
     << "_PRIME_SAMPLES > 0 (a delay's fraction over a half): after init, the references of the\n"
     << " * " << N
     << "_PRIME_SAMPLES samples before the first inverse step's, in order; returns -1 when none is "
        "wanted. */\n"
     << "static inline int " << name << "_inverse_prime(" << name
     << "_state *s, double y_desired) {\n"
     << "  return pzk_chain_inverse_prime(" << name << "_blocks_, " << N
     << "_BLOCKS, s->c, s->d, s->t, &s->ctl, y_desired);\n}\n\n"
     << "#endif /* " << N << "_H_ */\n";
}

}  // namespace

std::string ExportHeader(const records::Stepper& st, const std::string& name,
                         const std::string& comment) {
  if (!IsCIdentifier(name)) {
    throw InputError("--name '" + name +
                     "': must be a C identifier ([A-Za-z_][A-Za-z0-9_]*, at most 63 characters)");
  }
  const records::ModelSpec& m = st.spec();
  const std::string N = CUpper(name);
  const auto& blocks = st.blocks();
  const int nb = static_cast<int>(blocks.size());
  std::ostringstream os;
  std::string safe = comment;
  for (size_t i = 0; i + 1 < safe.size(); ++i)
    if (safe[i] == '*' && safe[i + 1] == '/') safe[i] = '_';
  WriteBanner(os, st, name, safe);
  double delay = 0;
  for (int i = 0; i < nb; ++i)
    if (blocks[i].kind == pzk::PZK_DELAY) delay = blocks[i].p[0];
  os << "#define " << N << "_U_MIN " << CHexLiteral(m.drive_min) << " /* "
     << io::FormatNumber(m.drive_min) << " " << m.drive_unit << " */\n"
     << "#define " << N << "_U_MAX " << CHexLiteral(m.drive_max) << " /* "
     << io::FormatNumber(m.drive_max) << " " << m.drive_unit << " */\n"
     << "#define " << N << "_DT_S " << CHexLiteral(m.dt) << "\n"
     << "#define " << N << "_DELAY_S " << CHexLiteral(delay) << "\n"
     << "#define " << N << "_PREVIEW_SAMPLES " << st.preview_samples() << "\n"
     << "#define " << N << "_PRIME_SAMPLES " << st.delay_horizon() << "\n"
     << "#define " << N << "_BLOCKS " << nb << "\n\n";
  WriteBlocks(os, st, name);
  WriteFunctions(os, st, name);
  return os.str();
}

}  // namespace pz::controller
