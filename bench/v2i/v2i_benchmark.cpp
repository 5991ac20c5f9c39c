// SPDX-License-Identifier: Apache-2.0
// Throughput of the RSU's per-datagram V2I path (unsigned baseline and signed: Ed25519 sign and
// verify, replay window) and of association at a busy intersection. The datagram benchmarks report
// cpu_per_msg: CPU time per message; 1000 vehicles announcing at 10 Hz (10,000 messages/s) cost
// 10,000 x cpu_per_msg of one core each second (e.g. 40 us -> 40 % of a core).
#include <benchmark/benchmark.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/random.h"
#include "tracking/association.h"
#include "v2i/announcement_validation.h"
#include "v2i/message_authenticator.h"
#include "v2i/message_signer.h"
#include "v2i/vehicle_registry.h"
#include "v2i/wire_codec.h"

namespace rsu::v2i {
namespace {

constexpr TimeNs kT0 = 1'700'000'000 * kNsPerSecond;
constexpr int kVehicles = 200;

VehicleAnnouncement announcement(std::uint64_t id, std::uint32_t sequence, TimeNs t) {
  VehicleAnnouncement a;
  a.vehicle_id = id;
  a.sequence = sequence;
  a.generation_time = t;
  a.size = {4.89, 1.92, 1.70};
  a.reference_offset = {-1.35, 0.0};
  a.pose = {static_cast<double>(id), 2.0 * static_cast<double>(id % 7), 0.4};
  a.pose_covariance = Eigen::Vector3d(0.04, 0.04, 0.001).asDiagonal();
  a.speed_mps = 8.0;
  a.yaw_rate_rps = 0.0;
  a.reply_to = {"192.0.2." + std::to_string(1 + id % 250), 47001};
  return a;
}

// Validation + registry upsert, as the daemon does after decoding: 200 vehicles at 10 Hz each.
void BM_ValidateAndUpsert(benchmark::State& state) {
  VehicleRegistryConfig config;
  config.rate_limit.bucket = {1e9, 1e9};  // measure the registry, not rejections
  VehicleRegistry registry(config);
  AnnouncementValidator validator;
  std::vector<VehicleAnnouncement> batch;
  std::vector<std::string> sources;
  for (int i = 0; i < kVehicles; ++i) {
    batch.push_back(announcement(static_cast<std::uint64_t>(i + 1), 0, kT0));
    sources.push_back("192.0.2." + std::to_string(1 + i % 250));
  }
  std::uint32_t round = 0;
  TimeNs now = kT0;
  for (auto _ : state) {
    ++round;
    now += 100 * kNsPerMs / kVehicles;
    for (int i = 0; i < kVehicles; ++i) {
      VehicleAnnouncement& a = batch[static_cast<std::size_t>(i)];
      a.sequence = round;
      a.generation_time = now;
      if (validator.check(a, now) == AnnouncementReason::kValid) {
        benchmark::DoNotOptimize(registry.upsert(a, sources[static_cast<std::size_t>(i)], now));
      }
    }
  }
  state.SetItemsProcessed(state.iterations() * kVehicles);
}
BENCHMARK(BM_ValidateAndUpsert);

// The whole datagram path: decode + validate + upsert.
void BM_DecodeValidateUpsert(benchmark::State& state) {
  VehicleRegistryConfig config;
  config.rate_limit.bucket = {1e9, 1e9};
  VehicleRegistry registry(config);
  AnnouncementValidator validator;
  std::vector<std::vector<std::uint8_t>> datagrams;
  constexpr int kRounds = 50;
  for (int r = 1; r <= kRounds; ++r) {
    for (int i = 0; i < kVehicles; ++i) {
      datagrams.push_back(encode_v2i_message(
          announcement(static_cast<std::uint64_t>(i + 1), static_cast<std::uint32_t>(r), kT0)));
    }
  }
  std::size_t next = 0;
  for (auto _ : state) {
    const DecodedMessage m = decode_v2i_message(datagrams[next]);
    next = (next + 1) % datagrams.size();
    if (next == 0) {
      state.PauseTiming();
      registry = VehicleRegistry(config);
      state.ResumeTiming();
    }
    if (const auto* a = std::get_if<VehicleAnnouncement>(&m.body)) {
      if (validator.check(*a, kT0) == AnnouncementReason::kValid) {
        benchmark::DoNotOptimize(registry.upsert(*a, a->reply_to.address, kT0));
      }
    }
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DecodeValidateUpsert);

// CPU seconds per message (an inverted rate over the iterations), printed with its unit.
void report_core_share(benchmark::State& state) {
  state.counters["cpu_per_msg"] = benchmark::Counter(
      static_cast<double>(state.iterations()), benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

security::SigningKey vehicle_key(int i) {
  security::Seed seed{};
  seed.fill(static_cast<std::uint8_t>(i));
  seed[1] = static_cast<std::uint8_t>(i >> 8);
  return security::SigningKey(seed);
}

// Baseline of the signed path below: the unsigned datagram path, decode + validate + upsert, per item.
void BM_UnsignedDatagramPath(benchmark::State& state) {
  BM_DecodeValidateUpsert(state);
  report_core_share(state);
}
BENCHMARK(BM_UnsignedDatagramPath);

// The vehicle's side: encode + Ed25519 sign one announcement.
void BM_EncodeAndSign(benchmark::State& state) {
  MessageSigner signer(vehicle_key(1));
  const VehicleAnnouncement a = announcement(1, 1, kT0);
  TimeNs now = kT0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(signer.encode(a, ++now));
  }
  state.SetItemsProcessed(state.iterations());
  report_core_share(state);
}
BENCHMARK(BM_EncodeAndSign);

// Ed25519 verification alone, over a signed announcement's bytes.
void BM_VerifySignature(benchmark::State& state) {
  const security::SigningKey key = vehicle_key(1);
  const std::vector<std::uint8_t> bytes = MessageSigner(key).encode(announcement(1, 1, kT0), kT0);
  const DecodedEnvelope e = decode_envelope(bytes);
  const std::vector<std::uint8_t> input = signing_input(e.envelope.payload);
  const auto* sig = reinterpret_cast<const std::uint8_t*>(e.envelope.signature.data());
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        security::verify_signature(key.public_key(), input, {sig, e.envelope.signature.size()}));
  }
  state.SetItemsProcessed(state.iterations());
  report_core_share(state);
}
BENCHMARK(BM_VerifySignature);

// The RSU's whole signed datagram path: authenticate (envelope, trust-list lookup, Ed25519 verify,
// payload, rights, time and sequence windows) + validate + upsert; 200 vehicles, each with its key.
void BM_SignedDatagramPath(benchmark::State& state) {
  VehicleRegistryConfig config;
  config.rate_limit.bucket = {1e9, 1e9};
  VehicleRegistry registry(config);
  AnnouncementValidator validator;
  security::TrustList trust;
  std::vector<MessageSigner> signers;
  for (int i = 0; i < kVehicles; ++i) {
    const security::SigningKey key = vehicle_key(i);
    trust.add({key.public_key(), security::SignerRole::kVehicle, {static_cast<std::uint64_t>(i + 1)}});
    signers.emplace_back(key);
  }
  MessageAuthenticator authenticator(SecurityConfig{}, trust);
  std::vector<std::vector<std::uint8_t>> datagrams;
  constexpr int kRounds = 50;
  for (int r = 1; r <= kRounds; ++r) {
    for (int i = 0; i < kVehicles; ++i) {
      const auto id = static_cast<std::uint64_t>(i + 1);
      datagrams.push_back(signers[static_cast<std::size_t>(i)].encode(
          announcement(id, static_cast<std::uint32_t>(r), kT0), kT0));
    }
  }
  std::size_t next = 0;
  std::size_t accepted = 0;
  for (auto _ : state) {
    const AuthenticatedMessage m = authenticator.authenticate(datagrams[next], kT0);
    next = (next + 1) % datagrams.size();
    if (next == 0) {
      state.PauseTiming();  // the same datagrams again: a fresh receiver, or they are replays
      registry = VehicleRegistry(config);
      authenticator = MessageAuthenticator(SecurityConfig{}, trust);
      state.ResumeTiming();
    }
    if (const auto* a = std::get_if<VehicleAnnouncement>(&m.message.body); a && m.accepted()) {
      ++accepted;
      if (validator.check(*a, kT0) == AnnouncementReason::kValid) {
        benchmark::DoNotOptimize(registry.upsert(*a, a->reply_to.address, kT0));
      }
    }
  }
  if (accepted != static_cast<std::size_t>(state.iterations())) {
    state.SkipWithError("a genuine datagram was refused");
  }
  state.SetItemsProcessed(state.iterations());
  report_core_share(state);
}
BENCHMARK(BM_SignedDatagramPath);

// Association of N clusters with N registered vehicles, spread over a 100 m x 100 m junction.
void BM_Associate(benchmark::State& state) {
  const auto n = static_cast<std::size_t>(state.range(0));
  std::vector<tracking::VehicleHypothesis> vehicles(n);
  std::vector<perception::Detection> clusters(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = 100.0 * uniform_open01(mix64(2 * i));
    const double y = 100.0 * uniform_open01(mix64(2 * i + 1));
    const auto noise = standard_normal_pair(5, 0, i);
    vehicles[i].vehicle_id = i + 1;
    vehicles[i].centre = {x + 0.3 * noise.a, y + 0.3 * noise.b};
    vehicles[i].covariance = Eigen::Vector3d(0.09, 0.09, 0.01).asDiagonal();
    vehicles[i].size = {4.89, 1.92, 1.70};
    perception::RectangleFit& fit = clusters[(i * 7) % n].fit;
    fit.status = perception::FitStatus::ok;
    fit.center = {x, y};
    fit.length0 = 4.5;
    fit.length1 = 1.8;
    fit.corners.fill(Eigen::Vector2d::Zero());  // unused by association
  }
  for (auto _ : state) {
    benchmark::DoNotOptimize(tracking::associate(clusters, vehicles));
  }
}
BENCHMARK(BM_Associate)->Arg(10)->Arg(50)->Arg(200);

}  // namespace
}  // namespace rsu::v2i
