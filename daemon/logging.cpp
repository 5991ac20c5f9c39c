// SPDX-License-Identifier: Apache-2.0
#include "daemon/logging.h"

#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <memory>

namespace rsu::daemon {

namespace {

// %* -> "<N>", the syslog priority of the message's level (sd-daemon(3) SD_ERR = 3 ... SD_DEBUG = 7).
class PriorityFlag : public spdlog::custom_flag_formatter {
 public:
  void format(const spdlog::details::log_msg& msg, const std::tm&, spdlog::memory_buf_t& dest) override {
    const char* text = "<6>";
    switch (msg.level) {
      case spdlog::level::trace:
      case spdlog::level::debug:
        text = "<7>";
        break;
      case spdlog::level::info:
        text = "<6>";
        break;
      case spdlog::level::warn:
        text = "<4>";
        break;
      case spdlog::level::err:
        text = "<3>";
        break;
      case spdlog::level::critical:
        text = "<2>";
        break;
      default:
        break;
    }
    dest.append(text, text + 3);
  }
  std::unique_ptr<custom_flag_formatter> clone() const override { return std::make_unique<PriorityFlag>(); }
};

}  // namespace

void setup_logging(const std::string& level) {
  const bool tty = isatty(STDERR_FILENO) == 1;
  auto sink = std::make_shared<spdlog::sinks::stderr_color_sink_mt>(tty ? spdlog::color_mode::automatic
                                                                        : spdlog::color_mode::never);
  auto logger = std::make_shared<spdlog::logger>("rsud", sink);
  if (tty) {
    logger->set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%^%l%$] %v");
  } else {
    auto formatter = std::make_unique<spdlog::pattern_formatter>();
    formatter->add_flag<PriorityFlag>('*').set_pattern("%*%l: %v");
    logger->set_formatter(std::move(formatter));
  }
  logger->set_level(spdlog::level::from_str(level));
  logger->flush_on(spdlog::level::trace);  // line by line: the journal and tests read it live
  spdlog::set_default_logger(logger);
}

}  // namespace rsu::daemon
