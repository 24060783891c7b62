// Writes the seed corpus of fuzz_master (fuzz/corpus/): one small valid input per message type
// and spec form, each prefixed with fuzz_master's selector byte. Usage: make_corpus DIR
// (fuzz/run.sh --regen-corpus runs it; the files are committed).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "service/security.h"
#include "service/wire_codec.h"

using namespace pz::job;
using namespace pz::service;
using pz::opt::Genome;
namespace kinds = pz::kinds;

namespace {

std::filesystem::path g_dir;

void Write(char selector, const std::string& name, const std::string& bytes) {
  std::ofstream f(g_dir / (std::to_string(static_cast<int>(selector)) + "-" + name),
                  std::ios::binary);
  f.put(selector);
  f << bytes;
}

JobSpec Synthetic() {
  JobSpec s;
  s.name = "fuzz";
  s.seed = 3;
  SyntheticProblem p;
  p.genome_bits = 24;
  s.problem = p;
  GaSettings ga;
  ga.population = 8;
  ga.generations = 3;
  s.ga = ga;
  return s;
}

JobSpec TinyHgann() {
  JobSpec s = Synthetic();
  HgannProblem h;
  for (int i = 0; i < 2; ++i) {
    HgannCaseSpec c;
    c.number = i + 1;
    c.amplitude_v = 50 + 25 * i;
    c.frequency_hz = 1 + i;
    c.role = i == 0 ? CaseRole::kTrain : CaseRole::kValidate;
    c.sample_rate_hz = 40;
    for (int k = 0; k < 12; ++k) c.angle_deg.push_back(0.5 * ((k * 7 + i) % 5) - 1.0);
    h.cases.push_back(c);
  }
  h.ranges_preset = "default";
  h.ranges.push_back({"mu", 0.1, 2.0});
  h.geometry["tip_length_m"] = 0.02;
  s.problem = h;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: make_corpus DIR\n");
    return 2;
  }
  g_dir = argv[1];
  std::filesystem::create_directories(g_dir);

  WorkerMsg w;
  w.type = WorkerMsg::Type::kReady;
  w.threads = 4;
  w.host = "node1";
  w.pid = 1234;
  Write(0, "ready", EncodeWorkerToMaster(w));
  w = {};
  w.type = WorkerMsg::Type::kHeartbeat;
  Write(0, "heartbeat", EncodeWorkerToMaster(w));
  w = {};
  w.type = WorkerMsg::Type::kContextRequest;
  w.context_hash = ContentHash("x");
  Write(0, "context-request", EncodeWorkerToMaster(w));
  w = {};
  w.type = WorkerMsg::Type::kResult;
  w.result.lease_id = 7;
  w.result.job_id = "j0123456789abcde";
  w.result.generation = 2;
  w.result.indices = {0, 5};
  w.result.results = {{1.5, FitnessStatus::kOk, ""}, {1e9, FitnessStatus::kPenalized, "unstable"}};
  w.result.eval_seconds = 0.25;
  Write(0, "result", EncodeWorkerToMaster(w));
  w = {};
  w.type = WorkerMsg::Type::kDisconnect;
  w.reason = "bye";
  Write(0, "disconnect", EncodeWorkerToMaster(w));

  ClientRequestMsg c;
  c.type = ClientRequestMsg::Type::kSubmit;
  c.spec = Synthetic();
  c.client_token = "t";
  Write(1, "submit-synthetic", EncodeClientRequest(c));
  c.spec = TinyHgann();
  Write(1, "submit-hgann", EncodeClientRequest(c));
  for (auto [t, n] : {std::pair{ClientRequestMsg::Type::kStatus, "status"},
                      {ClientRequestMsg::Type::kWatch, "watch"},
                      {ClientRequestMsg::Type::kCancel, "cancel"},
                      {ClientRequestMsg::Type::kList, "list"},
                      {ClientRequestMsg::Type::kFetch, "fetch"},
                      {ClientRequestMsg::Type::kPing, "ping"}}) {
    ClientRequestMsg r;
    r.type = t;
    r.request_id = 9;
    r.job_id = "j0123456789abcde";
    r.count = 3;
    Write(1, n, EncodeClientRequest(r));
  }

  Write(2, "synthetic", EncodeJobSpec(Synthetic()));
  Write(2, "hgann", EncodeJobSpec(TinyHgann()));
  Write(3, "synthetic.json", JobSpecToJson(Synthetic()));
  Write(3, "hgann.json", JobSpecToJson(TinyHgann()));

  WorkerMsg m;
  m.type = WorkerMsg::Type::kBatch;
  m.batch.lease_id = 3;
  m.batch.job_id = "j0123456789abcde";
  m.batch.generation = 1;
  m.batch.context_hash = ContentHash("x");
  m.batch.indices = {1, 2};
  m.batch.genomes = {Genome{{0, 1, 1, 0}, {}}, Genome{{1, 1, 0, 0}, {}}};
  m.batch.deadline_s = 10;
  Write(4, "batch", EncodeMasterToWorker(m));
  m = {};
  m.type = WorkerMsg::Type::kContext;
  m.context_spec = EncodeJobSpec(TinyHgann());
  m.context_hash = ContentHash(m.context_spec);
  Write(4, "context", EncodeMasterToWorker(m));

  Write(5, "key",
        "#   ZeroMQ CURVE **Secret** Certificate\nmetadata\ncurve\n"
        "    public-key = \"rq:rM>}U?@Lns47E1%kR.o@n%FcmmsL/@{H8]yf7\"\n"
        "    secret-key = \"JTKVSB%%)wK0E.X)V>+}o?pNmC{O&4W4b!Ni{Lh6\"\n");
  return 0;
}
