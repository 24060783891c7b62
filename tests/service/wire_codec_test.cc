// The one codec (service/wire_codec.h): every envelope a worker, a client or the master sends
// survives encode → decode → encode unchanged, with its fields; what does not decode is a named
// status, never a crash; versions are checked; stored files detect alteration.
#include <gtest/gtest.h>

#include <random>

#include "hgann/hgann_job.h"
#include "io/network_io.h"
#include "model/chromosome.h"
#include "service/wire_codec.h"
#include "tests/testing/hgann_spec.h"
#include "wire.pb.h"

namespace pz::service {
namespace {

opt::Genome G(int bits, uint32_t seed, std::vector<double> reals = {}) {
  opt::Genome g;
  for (int i = 0; i < bits; ++i) g.bits.push_back(static_cast<uint8_t>((seed >> (i % 32)) & 1u));
  g.reals = std::move(reals);
  return g;
}

template <typename M, typename Enc, typename Dec>
M RoundTrip(const M& m, Enc enc, Dec dec) {
  const std::string bytes = enc(m);
  M back;
  const Status s = dec(bytes, &back);
  EXPECT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(enc(back), bytes) << "re-encoding differs";
  return back;
}

TEST(WireCodec, WorkerEnvelopesRoundTrip) {
  WorkerMsg ready;
  ready.type = WorkerMsg::Type::kReady;
  ready.threads = 8;
  ready.host = "node-3";
  ready.pid = 4242;
  ready.arithmetic = "piezoid 0.1.0; x86-64-v3; glibc 2.36";
  auto r = RoundTrip(ready, EncodeWorkerToMaster, DecodeWorkerToMaster);
  EXPECT_EQ(r.type, WorkerMsg::Type::kReady);
  EXPECT_EQ(r.threads, 8);
  EXPECT_EQ(r.host, "node-3");
  EXPECT_EQ(r.pid, 4242);
  EXPECT_EQ(r.arithmetic, ready.arithmetic);

  WorkerMsg result;
  result.type = WorkerMsg::Type::kResult;
  result.result.lease_id = 77;
  result.result.job_id = "j1";
  result.result.generation = 12;
  result.result.indices = {3, 9};
  result.result.results = {{1.25, opt::FitnessStatus::kOk, {}, {0.5, -0.25}},
                           {1e9, opt::FitnessStatus::kPenalized, "unbounded_hysteresis"}};
  result.result.eval_seconds = 0.0125;
  r = RoundTrip(result, EncodeWorkerToMaster, DecodeWorkerToMaster);
  EXPECT_EQ(r.result.indices, (std::vector<int>{3, 9}));
  EXPECT_EQ(r.result.results[0].residuals, (std::vector<double>{0.5, -0.25}));
  EXPECT_EQ(r.result.results[1].status, opt::FitnessStatus::kPenalized);
  EXPECT_EQ(r.result.results[1].reason, "unbounded_hysteresis");

  WorkerMsg batch;
  batch.type = WorkerMsg::Type::kBatch;
  batch.batch.lease_id = 5;
  batch.batch.job_id = "j2";
  batch.batch.generation = 3;
  batch.batch.context_hash = ContentHash("spec");
  batch.batch.indices = {0, 1};
  batch.batch.genomes = {G(1415, 0xdeadbeef), G(13, 7, {0.5, 1e-300})};
  batch.batch.deadline_s = 60;
  auto b = RoundTrip(batch, EncodeMasterToWorker, DecodeMasterToWorker);
  EXPECT_EQ(b.batch.genomes[0], batch.batch.genomes[0]);
  EXPECT_EQ(b.batch.genomes[1], batch.batch.genomes[1]);

  WorkerMsg context;
  context.type = WorkerMsg::Type::kContext;
  context.context_hash = "abc";
  context.context_spec = EncodeJobSpec(testing::NominalHgannSpec(10, 1));
  b = RoundTrip(context, EncodeMasterToWorker, DecodeMasterToWorker);
  EXPECT_EQ(b.context_spec, context.context_spec);
}

// Genomes are packed eight bits at a time: every length, every bit pattern, the same bytes on the
// wire as one bit at a time (bit i in byte i/8 at position i%8), and back.
TEST(WireCodec, GenomesPackBitForBitAtEveryLength) {
  std::mt19937 rng(5);
  for (int bits = 0; bits <= 200; ++bits) {
    for (int trial = 0; trial < 4; ++trial) {
      opt::Genome g;
      for (int i = 0; i < bits; ++i) g.bits.push_back(static_cast<uint8_t>(rng() & 1u));
      if (trial == 3)  // any nonzero byte is a set bit
        for (auto& b : g.bits) b = b ? static_cast<uint8_t>(1 + rng() % 255) : 0;
      std::string expected((bits + 7) / 8, '\0');
      for (int i = 0; i < bits; ++i)
        if (g.bits[i]) expected[i / 8] = static_cast<char>(expected[i / 8] | (1u << (i % 8)));
      WorkerMsg m;
      m.type = WorkerMsg::Type::kBatch;
      m.batch.lease_id = 1;
      m.batch.job_id = "j";
      m.batch.indices = {0};
      m.batch.genomes = {g};
      pz::wire::MasterToWorker wire;
      ASSERT_TRUE(wire.ParseFromString(EncodeMasterToWorker(m)));
      ASSERT_EQ(wire.batch().tasks_size(), 1);
      EXPECT_EQ(wire.batch().tasks(0).genome().bits(), expected)
          << bits << " bits, trial " << trial;
      WorkerMsg back;
      ASSERT_TRUE(DecodeMasterToWorker(EncodeMasterToWorker(m), &back).ok());
      ASSERT_EQ(back.batch.genomes.size(), 1u);
      for (auto& b : g.bits) b = b ? 1 : 0;
      EXPECT_EQ(back.batch.genomes[0].bits, g.bits) << bits << " bits, trial " << trial;
    }
  }
}

// A lease written from a generation's packed tasks (the master's path) is the batch message
// EncodeMasterToWorker writes for the same tasks, field for field: any subset of positions in
// any order, genomes of every size (multi-byte lengths), reals, and an empty lease.
TEST(WireCodec, LeasesFromPackedTasksAreTheEncodedBatch) {
  std::vector<opt::Genome> genomes = {G(1415, 0xdeadbeef), G(13, 7, {0.5, 1e-300}), G(0, 0),
                                      G(64, 99), G(1415, 0x12345678)};
  for (int i = 0; i < 200; ++i)
    genomes.push_back(G(1415, 0x9e3779b9u * static_cast<uint32_t>(i + 1)));
  std::vector<int> indices(genomes.size());
  for (size_t i = 0; i < indices.size(); ++i)
    indices[i] = static_cast<int>(3 * i + (i % 2 ? 1000000 : 0));
  const PackedTasks packed(genomes, indices);
  ASSERT_EQ(packed.size(), static_cast<int>(genomes.size()));
  std::vector<int> all(genomes.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(all.size() - 1 - i);
  for (const std::vector<int>& positions : {std::vector<int>{}, std::vector<int>{0},
                                            std::vector<int>{2}, std::vector<int>{4, 1, 3}, all}) {
    WorkerMsg m;
    m.type = WorkerMsg::Type::kBatch;
    m.batch.lease_id = 0x123456789abcULL;
    m.batch.job_id = std::string(300, 'j');
    m.batch.generation = 41;
    m.batch.context_hash = ContentHash("spec");
    m.batch.deadline_s = 12.5;
    for (int p : positions) {
      m.batch.indices.push_back(indices[p]);
      m.batch.genomes.push_back(genomes[p]);
    }
    const size_t task_bytes = packed.Bytes(positions);
    std::string frame = PackedBatchHead(m.batch, task_bytes);
    const size_t head = frame.size();
    frame.resize(head + task_bytes);
    EXPECT_EQ(packed.Write(positions, frame.data() + head), frame.data() + frame.size());
    pz::wire::MasterToWorker from_packed, encoded;
    ASSERT_TRUE(from_packed.ParseFromString(frame)) << positions.size() << " tasks";
    ASSERT_TRUE(encoded.ParseFromString(EncodeMasterToWorker(m)));
    EXPECT_EQ(from_packed.SerializeAsString(), encoded.SerializeAsString())
        << positions.size() << " tasks";
    WorkerMsg back;
    ASSERT_TRUE(DecodeMasterToWorker(frame, &back).ok());
    EXPECT_EQ(back.batch.lease_id, m.batch.lease_id);
    EXPECT_EQ(back.batch.job_id, m.batch.job_id);
    EXPECT_EQ(back.batch.deadline_s, 12.5);
    EXPECT_EQ(back.batch.indices, m.batch.indices);
    for (auto& g : m.batch.genomes)
      for (auto& b : g.bits) b = b ? 1 : 0;
    EXPECT_EQ(back.batch.genomes, m.batch.genomes);
  }
}

TEST(WireCodec, ClientRequestsRoundTrip) {
  ClientRequestMsg submit;
  submit.type = ClientRequestMsg::Type::kSubmit;
  submit.request_id = 99;
  submit.spec = testing::NominalHgannSpec(20, 3);
  submit.client_token = "tok";
  auto s = RoundTrip(submit, EncodeClientRequest, DecodeClientRequest);
  EXPECT_EQ(s.request_id, 99u);
  EXPECT_EQ(s.spec_bytes, EncodeJobSpec(submit.spec));  // what the job id is computed from
  EXPECT_TRUE(s.decode_violations.empty());

  ClientRequestMsg prune;
  prune.type = ClientRequestMsg::Type::kPrune;
  prune.job_ids = {"ja", "jb"};
  prune.older_than_s = 86400;
  prune.keep = 3;
  prune.dry_run = true;
  auto p = RoundTrip(prune, EncodeClientRequest, DecodeClientRequest);
  EXPECT_EQ(p.job_ids, prune.job_ids);
  EXPECT_EQ(p.keep, 3);
  EXPECT_TRUE(p.dry_run);

  ClientRequestMsg eval;
  eval.type = ClientRequestMsg::Type::kEvaluate;
  eval.job_id = "js";
  eval.batch_seq = 4;
  eval.genomes = {G(0, 0, {1, 2, 3})};
  auto e = RoundTrip(eval, EncodeClientRequest, DecodeClientRequest);
  EXPECT_EQ(e.genomes[0].reals, (std::vector<double>{1, 2, 3}));

  for (auto t : {ClientRequestMsg::Type::kStatus, ClientRequestMsg::Type::kWatch,
                 ClientRequestMsg::Type::kCancel, ClientRequestMsg::Type::kClose}) {
    ClientRequestMsg m;
    m.type = t;
    m.job_id = "jx";
    EXPECT_EQ(RoundTrip(m, EncodeClientRequest, DecodeClientRequest).job_id, "jx");
  }
}

TEST(WireCodec, ClientRepliesRoundTripWithNetworksAndStatusFields) {
  ClientReplyMsg fetch;
  fetch.type = ClientReplyMsg::Type::kFetch;
  fetch.request_id = 7;
  fetch.info.job_id = "jf";
  fetch.info.state = JobState::kSucceeded;
  fetch.info.notice = "checkpoint.pb: checksum mismatch; resumed from checkpoint.prev.pb";
  fetch.info.storage_error = "cannot open checkpoint.pb.tmp";
  fetch.info.storage_error_since_unix_s = 1.7e9;
  fetch.info.archived = true;
  fetch.info.ended_unix_s = 1.8e9;
  fetch.best = {{0, G(1415, 3), {2.5, opt::FitnessStatus::kOk, {}}}};
  GenerationRecord rec;
  rec.generation = 1;
  rec.best_cost = 2.5;
  fetch.log = {rec};
  fetch.spec = testing::NominalHgannSpec(10, 1);
  std::vector<model::Network> nets;
  ASSERT_TRUE(hgann::HgannJobKind().networks(*fetch.spec, {&fetch.best[0].genome, 1}, &nets).ok());
  io::SavedNetwork n;
  n.network = nets[0];
  n.chromosome = fetch.best[0].genome.bits;
  n.provenance.job_id = "jf";
  n.provenance.fitness = 2.5;
  fetch.networks = {n};
  auto f = RoundTrip(fetch, EncodeClientReply, DecodeClientReply);
  EXPECT_EQ(f.request_id, 7u);
  EXPECT_EQ(f.info.notice, fetch.info.notice);
  EXPECT_EQ(f.info.storage_error, fetch.info.storage_error);
  EXPECT_TRUE(f.info.archived);
  EXPECT_EQ(f.info.ended_unix_s, 1.8e9);
  ASSERT_EQ(f.networks.size(), 1u);
  EXPECT_EQ(f.networks[0], n);

  ClientReplyMsg event;
  event.type = ClientReplyMsg::Type::kEvent;
  event.request_id = 55;  // the Watch's
  event.event.job_id = "je";
  event.event.state = JobState::kRunning;
  event.event.record = rec;
  event.event.storage_error = "disk full";
  auto ev = RoundTrip(event, EncodeClientReply, DecodeClientReply);
  EXPECT_EQ(ev.request_id, 55u);
  EXPECT_EQ(ev.event.storage_error, "disk full");

  ClientReplyMsg prune;
  prune.type = ClientReplyMsg::Type::kPrune;
  prune.pruned = {"j1"};
  prune.refused = {{"j2", "running: cancel it first"}};
  auto pr = RoundTrip(prune, EncodeClientReply, DecodeClientReply);
  EXPECT_EQ(pr.pruned, prune.pruned);
  EXPECT_EQ(pr.refused, prune.refused);

  // The dashboard's workers table and the median of a generation record.
  ClientReplyMsg workers;
  workers.type = ClientReplyMsg::Type::kWorkers;
  workers.workers_snapshot.workers = {{"00aa", "node-3", "worker-key",
                                       "piezoid 0.1.0; x86-64-v3; glibc 2.36", 4242, 8, 1.5e-4, 2,
                                       37, 12345, 1.7e9, true}};
  workers.workers_snapshot.departed = {
      {"00bb", "node-4", "lost (missed its heartbeats)", 77, 1.7e9 + 5, 99}};
  workers.workers_snapshot.leases_sent = 10;
  workers.workers_snapshot.tasks_done = 20;
  workers.workers_snapshot.results_ignored = 3;
  workers.workers_snapshot.bad_frames = 1;
  workers.workers_snapshot.uptime_s = 60.5;
  auto wr = RoundTrip(workers, EncodeClientReply, DecodeClientReply);
  EXPECT_EQ(wr.type, ClientReplyMsg::Type::kWorkers);
  EXPECT_EQ(wr.workers_snapshot, workers.workers_snapshot);
  ClientReplyMsg with_median;
  with_median.type = ClientReplyMsg::Type::kFetch;
  GenerationRecord median_rec;
  median_rec.generation = 7;
  median_rec.median_cost = 0.25;
  with_median.log = {median_rec};
  EXPECT_EQ(RoundTrip(with_median, EncodeClientReply, DecodeClientReply).log.at(0).median_cost,
            0.25);
}

TEST(WireCodec, LiveViewRequestsRoundTrip) {
  ClientRequestMsg fetch;
  fetch.type = ClientRequestMsg::Type::kFetch;
  fetch.job_id = "jf";
  fetch.log_only = true;
  fetch.log_from = 123;
  auto f = RoundTrip(fetch, EncodeClientRequest, DecodeClientRequest);
  EXPECT_TRUE(f.log_only);
  EXPECT_EQ(f.log_from, 123u);
  ClientRequestMsg workers;
  workers.type = ClientRequestMsg::Type::kWorkers;
  EXPECT_EQ(RoundTrip(workers, EncodeClientRequest, DecodeClientRequest).type,
            ClientRequestMsg::Type::kWorkers);
}

TEST(WireCodec, WhatDoesNotDecodeIsNamed) {
  WorkerMsg w;
  ClientRequestMsg c;
  ClientReplyMsg r;
  for (const std::string& junk : {std::string("\xff\xff\xff"), std::string(64, '\x08')}) {
    EXPECT_FALSE(DecodeWorkerToMaster(junk, &w).ok());
    EXPECT_FALSE(DecodeClientRequest(junk, &c).ok());
  }
  // Another protocol version: named, and answered CODE_VERSION_MISMATCH.
  pz::wire::ClientRequest v;
  v.set_version(2);
  v.mutable_list();
  Status s = DecodeClientRequest(v.SerializeAsString(), &c);
  EXPECT_EQ(DecodeFailureCode(s), WireCode::kVersionMismatch) << s.message();
  // A genome whose packed bits do not match its count.
  pz::wire::ClientRequest e;
  e.set_version(1);
  auto* g = e.mutable_evaluate()->add_genomes();
  g->set_bit_count(20);
  g->set_bits("x");
  s = DecodeClientRequest(e.SerializeAsString(), &c);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("bits"), std::string::npos) << s.message();
  // A negative prune rule.
  pz::wire::ClientRequest p;
  p.set_version(1);
  p.mutable_prune()->set_keep(-1);
  s = DecodeClientRequest(p.SerializeAsString(), &c);
  EXPECT_NE(s.message().find("prune.keep = -1"), std::string::npos) << s.message();
  // A fetched network that is not one.
  pz::wire::ClientReply f;
  f.set_version(1);
  f.set_code(pz::wire::CODE_OK);
  f.mutable_fetch()->add_networks()->set_hidden(42);
  s = DecodeClientReply(f.SerializeAsString(), &r);
  EXPECT_NE(s.message().find("fetch.networks[0]"), std::string::npos) << s.message();
  // Evaluate results out of order.
  pz::wire::ClientReply ev;
  ev.set_version(1);
  ev.set_code(pz::wire::CODE_OK);
  ev.mutable_evaluate()->add_results()->set_index(1);
  s = DecodeClientReply(ev.SerializeAsString(), &r);
  EXPECT_NE(s.message().find("evaluate.results[0].index"), std::string::npos) << s.message();
}

TEST(WireCodec, SpecsEncodeDeterministicallyAndStoredFilesDetectAlteration) {
  const job::JobSpec a = testing::NominalHgannSpec(10, 1);
  job::JobSpec b = a;
  auto& h = std::get<job::HgannProblem>(b.problem);
  h.geometry = {{"tip_length_m", 0.02}, {"n_active", 6}};
  job::JobSpec c = b;
  std::get<job::HgannProblem>(c.problem).geometry = {{"n_active", 6}, {"tip_length_m", 0.02}};
  EXPECT_EQ(EncodeJobSpec(b), EncodeJobSpec(c));  // map order does not change the bytes (job ids)
  EXPECT_EQ(ContentHash(EncodeJobSpec(b)), ContentHash(EncodeJobSpec(c)));

  const std::string payload = EncodeJobSpec(a);
  const std::string file = EncodeStoredFile("pz.wire.JobSpec", payload);
  std::string out;
  ASSERT_TRUE(DecodeStoredFile(file, "pz.wire.JobSpec", &out).ok());
  EXPECT_EQ(out, payload);
  EXPECT_EQ(DecodeStoredFile(file, "pz.wire.JobCheckpoint", &out).code(), StatusCode::kDataLoss);
  std::string flipped = file;
  flipped[flipped.size() / 2] ^= 0x04;
  const Status s = DecodeStoredFile(flipped, "pz.wire.JobSpec", &out);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_EQ(DecodeStoredFile(payload, "pz.wire.JobSpec", &out).code(),
            StatusCode::kNotFound);  // a bare payload
}

}  // namespace
}  // namespace pz::service
