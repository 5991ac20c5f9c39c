// SPDX-License-Identifier: Apache-2.0
// The rsu-vehicle CLI end to end, signed: NDT poses in, a fake RSU (plain UDP socket) that verifies each
// announcement against the vehicle key the test generated and answers with a correction signed by its
// RSU key, from the test's own truth; fused poses and a corrections file out.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>
#include <variant>

#include "../v2i/test_keys.h"
#include "common/angles.h"
#include "common/random.h"
#include "fake_rsu.h"
#include "v2i/message_authenticator.h"
#include "v2i/message_signer.h"
#include "v2i/security/key_text.h"
#include "v2i/wire_codec.h"
#include "vehicle_client/clock.h"

namespace rsu::vehicle_client {
namespace {

namespace fs = std::filesystem;

constexpr std::uint64_t kVehicleId = 77;
constexpr TimeNs kStart = 1'700'000'000 * kNsPerSecond;
constexpr TimeNs kStep = 50 * kNsPerMs;
constexpr int kRows = 20;
constexpr double kSpeed = 10.0;
constexpr double kNdtSigma = 0.2;

double truth_x(TimeNs t) {
  return 5.0 + kSpeed * to_seconds(t - kStart);
}
constexpr double kTruthY = 3.0;

// Holds the vehicle's key file and a trust list naming the fake RSU's key (rsu id 3).
struct TempDir {
  fs::path path = fs::temp_directory_path() / ("rsu_vehicle_cli_" + std::to_string(::getpid()));
  v2i::security::SigningKey car = key_from(11);
  v2i::security::SigningKey rsu = key_from(12);
  TempDir() {
    fs::create_directories(path);
    std::ofstream(path / "car.key") << v2i::security::secret_key_text(car);
    std::ofstream(path / "trust.list")
        << v2i::security::trust_entry_text({rsu.public_key(), v2i::security::SignerRole::kRsu, {3}});
  }
  ~TempDir() { fs::remove_all(path); }
};

std::vector<std::vector<std::string>> read_csv(const fs::path& path, std::string& header) {
  std::ifstream in(path);
  std::getline(in, header);
  std::vector<std::vector<std::string>> rows;
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> fields;
    std::stringstream s(line);
    std::string field;
    while (std::getline(s, field, ',')) {
      fields.push_back(field);
    }
    rows.push_back(fields);
  }
  return rows;
}

std::string slurp(const fs::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Runs the CLI in a thread; returns its exit code. The caller plays the RSU meanwhile.
struct CliRun {
  std::atomic<bool> done{false};
  int exit_code = -1;
  std::thread thread;

  explicit CliRun(const std::string& command) {
    thread = std::thread([this, command] {
      const int status = std::system(command.c_str());
      exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
      done = true;
    });
  }
  ~CliRun() {
    if (thread.joinable()) {
      thread.join();
    }
  }
};

std::string command_line(const TempDir& dir, const test::FakeRsu& rsu, const std::string& input) {
  return std::string(RSU_VEHICLE_BIN) + " --vehicle-id " + std::to_string(kVehicleId) + " --rsu " +
         rsu.endpoint_text() + " --bind 127.0.0.1:0 --realtime --drain-ms 200 --announce-period-ms 0" +
         " --key " + (dir.path / "car.key").string() + " --trust-list " + (dir.path / "trust.list").string() +
         " --corrections " + (dir.path / "corrections.csv").string() + " < " + (dir.path / input).string() +
         " > " + (dir.path / "fused.csv").string() + " 2> " + (dir.path / "stderr.txt").string();
}

TEST(RsuVehicleCli, FusesTheFakeRsusCorrectionsAndBeatsNdt) {
  TempDir dir;
  std::vector<double> ndt_x(kRows);
  {
    std::ofstream ndt(dir.path / "ndt.csv");
    ndt << "time_ns,x,y,yaw\n";
    for (int k = 0; k < kRows; ++k) {
      const TimeNs t = kStart + k * kStep;
      const NormalPair n = standard_normal_pair(5, 0, static_cast<std::uint64_t>(k));
      ndt_x[static_cast<std::size_t>(k)] = truth_x(t) + kNdtSigma * n.a;
      ndt << t << "," << ndt_x[static_cast<std::size_t>(k)] << "," << kTruthY + kNdtSigma * n.b << ",0\n";
    }
  }
  test::FakeRsu rsu;
  CliRun run(command_line(dir, rsu, "ndt.csv"));

  // The RSU: one correction per announcement, swept 10 ms after the announced pose, from the truth.
  v2i::security::TrustList vehicles;
  vehicles.add({dir.car.public_key(), v2i::security::SignerRole::kVehicle, {kVehicleId}});
  v2i::MessageAuthenticator authenticator(v2i::SecurityConfig{}, vehicles);
  v2i::MessageSigner signer(dir.rsu);
  int announcements = 0;
  std::uint32_t sequence = 100;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (!run.done && std::chrono::steady_clock::now() < deadline) {
    const auto bytes = rsu.receive(1);
    if (!bytes) {
      continue;
    }
    const v2i::AuthenticatedMessage heard = authenticator.authenticate(*bytes, edge::host_now_ns());
    ASSERT_EQ(heard.verdict, v2i::AuthVerdict::kAccepted);
    const auto* a = std::get_if<v2i::VehicleAnnouncement>(&heard.message.body);
    ASSERT_NE(a, nullptr);
    ASSERT_EQ(a->vehicle_id, kVehicleId);
    EXPECT_DOUBLE_EQ(a->size.length_m, 4.89);  // the CLI's default box
    ++announcements;
    v2i::Correction c;
    c.rsu_id = 3;
    c.vehicle_id = kVehicleId;
    c.sequence = sequence++;
    c.sweep_time = a->generation_time + 10 * kNsPerMs;
    const NormalPair n = standard_normal_pair(6, 0, c.sequence);
    c.pose = {truth_x(c.sweep_time) + 0.03 * n.a, kTruthY + 0.03 * n.b, kPi};  // a box yaw, backwards
    c.pose_covariance = Eigen::Vector3d(0.03 * 0.03, 0.03 * 0.03, 0.02 * 0.02).asDiagonal();
    c.quality.points_used = 200;
    c.announcement_sequence = a->sequence;
    rsu.send_to(signer.encode(c, edge::host_now_ns()), a->reply_to.address, a->reply_to.port);
  }
  run.thread.join();
  ASSERT_EQ(run.exit_code, 0) << slurp(dir.path / "stderr.txt");
  EXPECT_EQ(announcements, kRows);

  std::string header;
  const auto fused = read_csv(dir.path / "fused.csv", header);
  EXPECT_EQ(header, "time_ns,x,y,yaw,source,sxx,syy,syaw,speed_mps,yaw_rate_rps");
  int ndt_rows = 0;
  int rsu_rows = 0;
  double ndt_sq = 0.0;
  double fused_sq = 0.0;
  for (const auto& row : fused) {
    ASSERT_EQ(row.size(), 10U);
    if (row[4] == "rsu") {
      ++rsu_rows;
      continue;
    }
    ASSERT_EQ(row[4], "ndt");
    const TimeNs t = std::stoll(row[0]);
    EXPECT_EQ(t, kStart + ndt_rows * kStep);
    if (ndt_rows >= kRows / 2) {  // after the filter settled
      const double dx = std::stod(row[1]) - truth_x(t);
      const double dy = std::stod(row[2]) - kTruthY;
      fused_sq += dx * dx + dy * dy;
      const NormalPair n = standard_normal_pair(5, 0, static_cast<std::uint64_t>(ndt_rows));
      ndt_sq += kNdtSigma * kNdtSigma * (n.a * n.a + n.b * n.b);
    }
    ++ndt_rows;
  }
  EXPECT_EQ(ndt_rows, kRows);
  EXPECT_GE(rsu_rows, kRows / 2);
  RecordProperty("ndt_rmse_m", std::to_string(std::sqrt(ndt_sq / (kRows / 2))));
  RecordProperty("fused_rmse_m", std::to_string(std::sqrt(fused_sq / (kRows / 2))));
  EXPECT_LT(std::sqrt(fused_sq), 0.7 * std::sqrt(ndt_sq));
  // The yaw stays forward although every box yaw said backwards (modulo pi).
  EXPECT_LT(std::abs(std::stod(fused.back()[3])), 0.1);

  const auto corrections = read_csv(dir.path / "corrections.csv", header);
  EXPECT_EQ(header.substr(0, 15), "time_ns,x,y,yaw");
  EXPECT_EQ(static_cast<int>(corrections.size()), kRows);
  int accepted = 0;
  for (const auto& row : corrections) {
    ASSERT_EQ(row.size(), 20U);
    EXPECT_EQ(row[10], "200");  // points_used
    accepted += row[19] == "accepted";
  }
  EXPECT_EQ(accepted, rsu_rows);
}

TEST(RsuVehicleCli, BadInputNamesTheLineAndFails) {
  TempDir dir;
  {
    std::ofstream ndt(dir.path / "bad.csv");
    ndt << "time_ns,x,y,yaw\n" << kStart << ",1,2,0\n" << kStart + kStep << ",1,oops,0\n";
  }
  test::FakeRsu rsu;
  CliRun run(command_line(dir, rsu, "bad.csv"));
  run.thread.join();
  EXPECT_EQ(run.exit_code, 1);
  const std::string err = slurp(dir.path / "stderr.txt");
  EXPECT_NE(err.find("line 3"), std::string::npos) << err;
  EXPECT_NE(err.find("oops"), std::string::npos) << err;
}

// Signed is the default: without keys the CLI refuses to start, naming the options; a broken key file
// is refused naming the file and line.
TEST(RsuVehicleCli, RefusesToRunWithoutKeysUnlessInsecure) {
  TempDir dir;
  const std::string base = std::string(RSU_VEHICLE_BIN) +
                           " --vehicle-id 1 --rsu 127.0.0.1:9 < /dev/null 2> " +
                           (dir.path / "stderr.txt").string() + " > /dev/null";
  EXPECT_EQ(WEXITSTATUS(std::system(base.c_str())), 2);
  EXPECT_NE(slurp(dir.path / "stderr.txt").find("--key and --trust-list are required"), std::string::npos)
      << slurp(dir.path / "stderr.txt");
  std::ofstream(dir.path / "bad.key") << "ed25519-secret-key 00\n";
  const std::string bad = std::string(RSU_VEHICLE_BIN) + " --vehicle-id 1 --rsu 127.0.0.1:9 --key " +
                          (dir.path / "bad.key").string() + " --trust-list " +
                          (dir.path / "trust.list").string() + " < /dev/null 2> " +
                          (dir.path / "stderr.txt").string() + " > /dev/null";
  EXPECT_EQ(WEXITSTATUS(std::system(bad.c_str())), 2);
  EXPECT_NE(slurp(dir.path / "stderr.txt").find("bad.key:1: key must be exactly 64 hex digits"),
            std::string::npos)
      << slurp(dir.path / "stderr.txt");
  const std::string insecure = std::string(RSU_VEHICLE_BIN) +
                               " --vehicle-id 1 --rsu 127.0.0.1:9 --insecure --drain-ms 0 < /dev/null 2> " +
                               (dir.path / "stderr.txt").string() + " > /dev/null";
  EXPECT_EQ(WEXITSTATUS(std::system(insecure.c_str())), 0);
  EXPECT_NE(slurp(dir.path / "stderr.txt").find("*** INSECURE MODE"), std::string::npos)
      << slurp(dir.path / "stderr.txt");
  EXPECT_NE(slurp(dir.path / "stderr.txt").find("authentication (insecure)"), std::string::npos)
      << slurp(dir.path / "stderr.txt");
}

}  // namespace
}  // namespace rsu::vehicle_client
