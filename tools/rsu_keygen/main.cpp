// SPDX-License-Identifier: Apache-2.0
// rsu-keygen: makes Ed25519 key pairs for signed V2I messages (proto/v2i.proto) and keeps trust lists
// (lib/v2i/security/trust_list.h). The secret key file is created with mode 0600. Nothing is ever
// overwritten without --force; a trust list only grows (one entry per key).
#include <fcntl.h>
#include <sodium.h>
#include <sys/stat.h>
#include <unistd.h>

#include <boost/program_options.hpp>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "io/text_file.h"
#include "tools/cli/version.h"
#include "v2i/security/ed25519.h"
#include "v2i/security/key_text.h"
#include "v2i/security/trust_list.h"

namespace {

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace rsu::v2i::security;

// A command line that cannot be run as given: exit code 2, as for every program's usage errors.
class UsageError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

constexpr const char* kAbout =
    "rsu-keygen: Ed25519 keys and trust lists for signed V2I messages.\n"
    "\n"
    "usage:\n"
    "  rsu-keygen NAME [--force] [--trust-list FILE --role rsu|vehicle --ids ID[,ID...]]\n"
    "      makes a key pair: NAME.key (the secret key, mode 0600: give it only to the signer) and\n"
    "      NAME.pub (the public key); with --trust-list, also adds the public key to FILE.\n"
    "  rsu-keygen --public-key NAME.pub --trust-list FILE --role rsu|vehicle --ids ID[,ID...]\n"
    "      adds an existing public key to FILE.\n"
    "\n"
    "A trust list is created when missing and only ever appended to; a key is listed once. The ids bind\n"
    "the key: a vehicle key may announce only the listed vehicle ids, an RSU key may sign corrections and\n"
    "advertisements only for the listed rsu ids. rsud and rsu-vehicle re-read their trust list on\n"
    "SIGHUP / start. The key id printed (and written in comments) is the last 8 bytes of SHA-256 over the\n"
    "public key, as carried in each signed datagram.\n"
    "\n"
    "options";

// The folders a key or trust list goes into, made when missing with mode 0755 whatever the umask (the
// trust list and public keys in them must stay readable by rsud's own user; the secret key alone is 0600,
// and reaches rsud as a systemd credential).
void make_parent_folders(const fs::path& file) {
  fs::path folder;
  for (const fs::path& part : file.parent_path()) {
    folder /= part;
    if (::mkdir(folder.c_str(), 0755) == 0) {
      if (::chmod(folder.c_str(), 0755) != 0)
        throw std::runtime_error("cannot set the mode of " + folder.string() + ": " + rsu::io::errno_text());
    } else if (errno != EEXIST) {
      throw std::runtime_error("cannot create the folder " + folder.string() + ": " + rsu::io::errno_text());
    }
  }
}

// Writes `text` to `path` with `mode`; refuses an existing file unless `force`.
void write_new_file(const fs::path& path, const std::string& text, mode_t mode, bool force) {
  make_parent_folders(path);
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (force ? O_TRUNC : O_EXCL);
  const int fd = ::open(path.c_str(), flags, mode);
  if (fd < 0) {
    if (errno == EEXIST)
      throw std::runtime_error(path.string() + " exists; not overwritten (use --force)");
    throw std::runtime_error("cannot create " + path.string() + ": " + std::strerror(errno));
  }
  // An existing file keeps its old mode under O_TRUNC: set it, so a secret key is never left readable.
  bool ok = ::fchmod(fd, mode) == 0;
  std::size_t written = 0;
  while (ok && written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    ok = n > 0;
    written += ok ? static_cast<std::size_t>(n) : 0;
  }
  ok = ::close(fd) == 0 && ok;
  if (!ok)
    throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(errno));
}

void add_to_trust_list(const fs::path& list, const TrustEntry& entry) {
  const std::string existing = fs::exists(list) ? rsu::io::read_whole_file(list) : std::string();
  std::string updated = existing;
  if (!updated.empty() && updated.back() != '\n')
    updated += '\n';
  if (existing.empty())
    updated += "# Trust list (rsu-keygen): <rsu|vehicle> <Ed25519 public key> <ids it may sign for>\n";
  updated += trust_entry_text(entry);
  // The whole result must parse: a malformed list or a key listed twice is refused, nothing written.
  parse_trust_list_text(updated, list.string());
  if (existing.empty()) {
    // A new list is public (mode 0644, whatever the umask): rsud's own user reads it.
    write_new_file(list, updated, 0644, true);
    return;
  }
  std::ofstream out(list, std::ios::app);
  if (!out || !(out << updated.substr(existing.size())) || !out.flush())
    throw std::runtime_error("cannot append to " + list.string() + ": " + rsu::io::errno_text());
}

int run(int argc, char** argv) {
  std::string name;
  std::string trust_list;
  std::string role_text;
  std::string ids_text;
  std::string public_key_path;
  po::options_description visible(kAbout);
  visible.add_options()("help,h", "show this help")("version", rsu::tools::cli::kVersionHelp)(
      "force", "overwrite existing key files")("trust-list", po::value<std::string>(&trust_list),
                                               "trust list file to add the public key to")(
      "role", po::value<std::string>(&role_text), "rsu or vehicle (with --trust-list)")(
      "ids", po::value<std::string>(&ids_text),
      "the ids the key may sign for, e.g. 7 or 7,8 (with --trust-list)")(
      "public-key", po::value<std::string>(&public_key_path), "an existing public key file to list");
  po::options_description all;
  all.add(visible).add_options()("name", po::value<std::string>(&name));
  po::positional_options_description positional;
  positional.add("name", 1);
  po::variables_map vm;
  po::store(po::command_line_parser(argc, argv).options(all).positional(positional).run(), vm);
  if (vm.count("help") || argc == 1) {
    (argc == 1 ? std::cerr : std::cout) << visible << "\n";
    return argc == 1 ? 2 : 0;  // nothing asked: a usage error, as in every program
  }
  po::notify(vm);
  if (name.empty() == public_key_path.empty())
    throw UsageError("give either NAME (make a key pair) or --public-key (list an existing key)");
  if (!public_key_path.empty() && trust_list.empty())
    throw UsageError("--public-key needs --trust-list");
  if (trust_list.empty() != role_text.empty() || trust_list.empty() != ids_text.empty())
    throw UsageError("--trust-list, --role and --ids go together");
  if (!role_text.empty() && role_text != "rsu" && role_text != "vehicle")
    throw UsageError("--role must be rsu or vehicle, got \"" + role_text + "\"");

  PublicKey public_key{};
  if (!name.empty()) {
    ensure_sodium_initialized();
    Seed seed{};
    randombytes_buf(seed.data(), seed.size());  // the OS's CSPRNG (getrandom)
    const SigningKey key(seed);
    sodium_memzero(seed.data(), seed.size());
    const bool force = vm.count("force") > 0;
    const fs::path secret_path = name + ".key";
    const fs::path public_path = name + ".pub";
    if (!force && (fs::exists(secret_path) || fs::exists(public_path)))
      throw std::runtime_error(name + ".key or " + name + ".pub exists; not overwritten (use --force)");
    write_new_file(secret_path, secret_key_text(key), 0600, force);
    write_new_file(public_path, public_key_text(key.public_key()), 0644, force);
    public_key = key.public_key();
    std::cout << "key id " << to_hex(key.key_id()) << ": wrote " << secret_path.string()
              << " (secret, mode 0600) and " << public_path.string() << "\n";
  } else {
    public_key = parse_public_key_text(rsu::io::read_whole_file(public_key_path), public_key_path);
  }
  if (!trust_list.empty()) {
    // Parse the ids with the trust list's own rules (a one-line list).
    const TrustList one =
        parse_trust_list_text(role_text + " " + to_hex(public_key) + " " + ids_text + "\n", "--ids");
    add_to_trust_list(trust_list, one.entries().begin()->second);
    std::cout << "listed key " << to_hex(key_id_of(public_key)) << " as " << role_text << " for " << ids_text
              << " in " << trust_list << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (rsu::tools::cli::print_version_if_asked(argc, argv, "rsu-keygen"))
    return 0;
  try {
    return run(argc, argv);
  } catch (const po::error& e) {  // unknown option, missing value
    std::cerr << "rsu-keygen: " << e.what() << " (see --help)\n";
    return 2;
  } catch (const UsageError& e) {
    std::cerr << "rsu-keygen: " << e.what() << " (see --help)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "rsu-keygen: " << e.what() << "\n";
    return 1;
  }
}
