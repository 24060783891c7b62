#include "io/network_io.h"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "model/chromosome.h"
#include "network.pb.h"

namespace pz::io {
namespace {

namespace pb = ::pz::proto;
using model::kNetworkInputs;
using model::kNetworkOutputs;

pb::NetworkTransferFunction TfToProto(model::TransferFunction tf) {
  return static_cast<pb::NetworkTransferFunction>(static_cast<int>(tf) + 1);
}

Status TfFromProto(int value, const std::string& field, model::TransferFunction* tf) {
  const int code = value - 1;
  if (!model::IsValidTransferCode(code)) {
    return InvalidArgument(FieldError(field, value,
                                      "must be a transfer function NETWORK_TF_HARDLIM (1) … "
                                      "NETWORK_TF_RADBAS (8)"));
  }
  *tf = model::TransferFromCode(code);
  return Status::Ok();
}

Status CountError(const char* field, int have, const std::string& expected_text, int expected) {
  std::ostringstream os;
  os << field << ": has " << have << " values, expected " << expected_text << " = " << expected;
  return InvalidArgument(os.str());
}

template <typename Repeated>
Status CheckFiniteValues(const Repeated& values, const char* field) {
  for (int i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values.Get(i))) {
      return InvalidArgument(FieldError(std::string(field) + "[" + std::to_string(i) + "]",
                                        values.Get(i), "must be finite"));
    }
  }
  return Status::Ok();
}

Status CheckName(const std::string& field, const std::string& have, const char* want) {
  if (have == want) return Status::Ok();
  return InvalidArgument(field + " = \"" + have + "\": expected \"" + want + "\"");
}

}  // namespace

NetworkFormat NetworkFormatForPath(const std::string& path) {
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return lower.size() >= 5 && lower.compare(lower.size() - 5, 5, ".json") == 0
             ? NetworkFormat::kJson
             : NetworkFormat::kBinary;
}

Status ValidateSavedNetwork(const SavedNetwork& saved) {
  Status s = saved.network.Validate();
  if (!s.ok()) return s;
  if (!std::isfinite(saved.provenance.fitness)) {
    return InvalidArgument(
        FieldError("provenance.fitness", saved.provenance.fitness, "must be finite"));
  }
  if (saved.chromosome.empty()) return Status::Ok();
  s = model::ValidateChromosome(saved.chromosome);
  if (!s.ok()) return s;
  const model::Network decoded =
      model::DecodeChromosome(saved.chromosome, saved.network.normalization, saved.network.ranges);
  if (!(decoded == saved.network)) {
    return InvalidArgument("chromosome: does not decode to the stored network (stored " +
                           saved.network.Describe() + ", chromosome " + decoded.Describe() +
                           "); the weights, transfer functions or H differ");
  }
  return Status::Ok();
}

void ToProto(const SavedNetwork& saved, pb::NetworkFile* out) {
  out->Clear();
  const model::Network& n = saved.network;
  const int h = n.hidden();
  out->set_format_version(kNetworkFormatVersion);
  out->set_hidden(h);
  for (model::TransferFunction tf : n.input_tf) out->add_input_tf(TfToProto(tf));
  for (model::TransferFunction tf : n.hidden_tf) out->add_hidden_tf(TfToProto(tf));
  for (model::TransferFunction tf : n.output_tf) out->add_output_tf(TfToProto(tf));
  for (int i = 0; i < n.w1.rows(); ++i) {
    for (int j = 0; j < n.w1.cols(); ++j) out->add_w1(n.w1(i, j));
  }
  for (int j = 0; j < n.c1.size(); ++j) out->add_c1(n.c1(j));
  for (int j = 0; j < n.w2.rows(); ++j) {
    for (int k = 0; k < n.w2.cols(); ++k) out->add_w2(n.w2(j, k));
  }
  for (int k = 0; k < n.c2.size(); ++k) out->add_c2(n.c2(k));
  const double lo[kNetworkInputs] = {n.normalization.amplitude_lo_v,
                                     n.normalization.frequency_lo_hz};
  const double hi[kNetworkInputs] = {n.normalization.amplitude_hi_v,
                                     n.normalization.frequency_hi_hz};
  for (int i = 0; i < kNetworkInputs; ++i) {
    pb::NetworkInput* in = out->add_inputs();
    in->set_name(model::InputName(i));
    in->set_unit(model::InputUnit(i));
    in->set_lo(lo[i]);
    in->set_hi(hi[i]);
  }
  for (int k = 0; k < kNetworkOutputs; ++k) {
    pb::NetworkParameter* p = out->add_parameters();
    p->set_name(model::OutputName(k));
    p->set_unit(model::OutputUnit(k));
    p->set_lower(n.ranges[k].lower);
    p->set_upper(n.ranges[k].upper);
  }
  if (!saved.chromosome.empty()) {
    const std::vector<uint8_t> packed = model::PackBits(saved.chromosome);
    out->set_chromosome(std::string(packed.begin(), packed.end()));
  }
  const NetworkProvenance& src = saved.provenance;
  pb::NetworkProvenance* prov = out->mutable_provenance();
  prov->set_job_id(src.job_id);
  prov->set_seed(src.seed);
  prov->set_generation(src.generation);
  prov->set_fitness(src.fitness);
  if (src.created_unix_ms != 0) {
    const int64_t ms = src.created_unix_ms;
    const int64_t sec = ms >= 0 ? ms / 1000 : -((-ms + 999) / 1000);  // floor
    prov->mutable_created()->set_seconds(sec);
    prov->mutable_created()->set_nanos(static_cast<int32_t>((ms - sec * 1000) * 1000000));
  }
  prov->set_piezoid_version(src.piezoid_version);
  for (const std::string& c : src.training_cases) prov->add_training_cases(c);
}

Status FromProto(const pb::NetworkFile& file, SavedNetwork* out) {
  if (file.format_version() != kNetworkFormatVersion) {
    return InvalidArgument(FieldError("format_version", file.format_version(),
                                      "unsupported (this reader knows version 1)"));
  }
  const int h = static_cast<int>(file.hidden());
  if (h < model::kMinHidden || h > model::kMaxHidden) {
    return InvalidArgument(FieldError("hidden", file.hidden(), "hidden-node count must be 2 … 9"));
  }
  if (file.input_tf_size() != kNetworkInputs)
    return CountError("input_tf", file.input_tf_size(), "2", 2);
  if (file.hidden_tf_size() != h) return CountError("hidden_tf", file.hidden_tf_size(), "H", h);
  if (file.output_tf_size() != kNetworkOutputs)
    return CountError("output_tf", file.output_tf_size(), "7", 7);
  if (file.w1_size() != kNetworkInputs * h) return CountError("w1", file.w1_size(), "2 x H", 2 * h);
  if (file.c1_size() != h) return CountError("c1", file.c1_size(), "H", h);
  if (file.w2_size() != h * kNetworkOutputs)
    return CountError("w2", file.w2_size(), "H x 7", 7 * h);
  if (file.c2_size() != kNetworkOutputs) return CountError("c2", file.c2_size(), "7", 7);
  if (file.inputs_size() != kNetworkInputs) return CountError("inputs", file.inputs_size(), "2", 2);
  if (file.parameters_size() != kNetworkOutputs) {
    return CountError("parameters", file.parameters_size(), "7", 7);
  }
  for (Status s : {CheckFiniteValues(file.w1(), "w1"), CheckFiniteValues(file.c1(), "c1"),
                   CheckFiniteValues(file.w2(), "w2"), CheckFiniteValues(file.c2(), "c2")}) {
    if (!s.ok()) return s;
  }

  SavedNetwork saved;
  model::Network& n = saved.network;
  for (int i = 0; i < kNetworkInputs; ++i) {
    Status s = TfFromProto(file.input_tf(i), "input_tf[" + std::to_string(i) + "]", &n.input_tf[i]);
    if (!s.ok()) return s;
  }
  n.hidden_tf.resize(h);
  for (int j = 0; j < h; ++j) {
    Status s =
        TfFromProto(file.hidden_tf(j), "hidden_tf[" + std::to_string(j) + "]", &n.hidden_tf[j]);
    if (!s.ok()) return s;
  }
  for (int k = 0; k < kNetworkOutputs; ++k) {
    Status s =
        TfFromProto(file.output_tf(k), "output_tf[" + std::to_string(k) + "]", &n.output_tf[k]);
    if (!s.ok()) return s;
  }
  n.w1.resize(kNetworkInputs, h);
  n.c1.resize(h);
  n.w2.resize(h, kNetworkOutputs);
  n.c2.resize(kNetworkOutputs);
  for (int i = 0; i < kNetworkInputs; ++i) {
    for (int j = 0; j < h; ++j) n.w1(i, j) = file.w1(h * i + j);
  }
  for (int j = 0; j < h; ++j) {
    n.c1(j) = file.c1(j);
    for (int k = 0; k < kNetworkOutputs; ++k) n.w2(j, k) = file.w2(kNetworkOutputs * j + k);
  }
  for (int k = 0; k < kNetworkOutputs; ++k) n.c2(k) = file.c2(k);

  for (int i = 0; i < kNetworkInputs; ++i) {
    const std::string field = "inputs[" + std::to_string(i) + "]";
    Status s = CheckName(field + ".name", file.inputs(i).name(), model::InputName(i));
    if (!s.ok()) return s;
  }
  n.normalization.amplitude_lo_v = file.inputs(0).lo();
  n.normalization.amplitude_hi_v = file.inputs(0).hi();
  n.normalization.frequency_lo_hz = file.inputs(1).lo();
  n.normalization.frequency_hi_hz = file.inputs(1).hi();
  for (int k = 0; k < kNetworkOutputs; ++k) {
    const std::string field = "parameters[" + std::to_string(k) + "]";
    Status s = CheckName(field + ".name", file.parameters(k).name(), model::OutputName(k));
    if (!s.ok()) return s;
    n.ranges[k] = {file.parameters(k).lower(), file.parameters(k).upper()};
  }

  if (!file.chromosome().empty()) {
    const std::string& c = file.chromosome();
    try {
      saved.chromosome = model::UnpackBits(
          std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(c.data()), c.size()),
          model::kChromosomeBits);
    } catch (const InputError& e) {
      return InvalidArgument("chromosome: " + e.status().message());
    }
  }
  const pb::NetworkProvenance& prov = file.provenance();
  saved.provenance.job_id = prov.job_id();
  saved.provenance.seed = prov.seed();
  saved.provenance.generation = prov.generation();
  saved.provenance.fitness = prov.fitness();
  if (prov.has_created()) {
    if (prov.created().nanos() < 0 || prov.created().nanos() > 999999999) {
      return InvalidArgument(
          FieldError("provenance.created.nanos", prov.created().nanos(), "must be 0 … 999999999"));
    }
    saved.provenance.created_unix_ms =
        prov.created().seconds() * 1000 + prov.created().nanos() / 1000000;
  }
  saved.provenance.piezoid_version = prov.piezoid_version();
  saved.provenance.training_cases.assign(prov.training_cases().begin(),
                                         prov.training_cases().end());

  Status s = ValidateSavedNetwork(saved);
  if (!s.ok()) return s;
  *out = std::move(saved);
  return Status::Ok();
}

Status SerializeNetwork(const SavedNetwork& saved, NetworkFormat format, std::string* out) {
  Status s = ValidateSavedNetwork(saved);
  if (!s.ok()) return s;
  pb::NetworkFile file;
  ToProto(saved, &file);
  if (format == NetworkFormat::kBinary) {
    if (!file.SerializeToString(out))
      return Internal("network file: protobuf serialisation failed");
    return Status::Ok();
  }
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = true;
  options.always_print_primitive_fields = true;
  options.preserve_proto_field_names = true;
  out->clear();
  auto js = google::protobuf::util::MessageToJsonString(file, out, options);
  if (!js.ok())
    return Internal("network file: JSON conversion failed: " + std::string(js.message()));
  return Status::Ok();
}

Status ParseNetwork(std::string_view data, NetworkFormat format, SavedNetwork* out) {
  pb::NetworkFile file;
  if (format == NetworkFormat::kBinary) {
    if (!file.ParseFromArray(data.data(), static_cast<int>(data.size()))) {
      return Status(StatusCode::kDataLoss, "not a NetworkFile protobuf (truncated or corrupt)");
    }
  } else {
    google::protobuf::util::JsonParseOptions options;
    options.ignore_unknown_fields = false;
    auto js = google::protobuf::util::JsonStringToMessage(
        google::protobuf::StringPiece(data.data(), data.size()), &file, options);
    if (!js.ok()) return InvalidArgument("not a NetworkFile JSON: " + std::string(js.message()));
  }
  return FromProto(file, out);
}

Status SaveNetwork(const SavedNetwork& saved, const std::string& path) {
  std::string data;
  Status s = SerializeNetwork(saved, NetworkFormatForPath(path), &data);
  if (!s.ok()) return Status(s.code(), path + ": " + s.message());
  const std::string tmp = path + ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) return NotFound(path + ": cannot open " + tmp + " for writing");
    f.write(data.data(), static_cast<std::streamsize>(data.size()));
    f.close();
    if (!f) return Internal(path + ": writing " + tmp + " failed");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    return Internal(path + ": cannot rename " + tmp + " into place");
  }
  return Status::Ok();
}

Status LoadNetwork(const std::string& path, SavedNetwork* out) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return NotFound(path + ": cannot open for reading");
  std::ostringstream buf;
  buf << f.rdbuf();
  Status s = ParseNetwork(buf.str(), NetworkFormatForPath(path), out);
  if (!s.ok()) return Status(s.code(), path + ": " + s.message());
  return Status::Ok();
}

}  // namespace pz::io
