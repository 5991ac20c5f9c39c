// SPDX-License-Identifier: Apache-2.0
// Typed topic, reader and writer over the C types idlc generates (dds/idl/*.idl): RAII handles,
// Cyclone errors as DdsError. ROS 2 topic names are "rt/<ros name>" on the wire (docs/design.md §5):
// ros_topic() makes them.
//
// Threading: a reader's `on_data_available` runs on a Cyclone thread. It must not touch the owner's
// state; rsud's use posts a "take now" to its io_context (daemon/dds_edge.h) and takes there.
#pragma once

#include <dds/dds.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "dds/dds_error.h"
#include "dds/participant.h"
#include "dds/qos_config.h"

namespace rsu::dds {

// "vehicles/7/pose" -> "rt/vehicles/7/pose" (a leading '/' is dropped, as ROS 2 does).
std::string ros_topic(const std::string& ros_name);

// Owns one Cyclone entity handle; deleting it deletes its children.
class Entity {
 public:
  Entity() = default;
  explicit Entity(dds_entity_t handle) : handle_(handle) {}
  ~Entity() { reset(); }
  Entity(Entity&& o) noexcept : handle_(std::exchange(o.handle_, 0)) {}
  Entity& operator=(Entity&& o) noexcept {
    if (this != &o) {
      reset();
      handle_ = std::exchange(o.handle_, 0);
    }
    return *this;
  }
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;
  dds_entity_t handle() const { return handle_; }
  void reset() {
    if (handle_ > 0)
      dds_delete(handle_);
    handle_ = 0;
  }

 private:
  dds_entity_t handle_ = 0;
};

// A topic of the type `descriptor` (idlc's <type>_desc) named `name` (wire name: use ros_topic()).
class Topic {
 public:
  Topic(const Participant& participant, const std::string& name, const dds_topic_descriptor_t& descriptor);
  dds_entity_t handle() const { return entity_.handle(); }
  const std::string& name() const { return name_; }

 private:
  std::string name_;
  Entity entity_;
};

// Reads samples of the C type T (which must match the topic's descriptor).
template <typename T>
class Reader {
 public:
  using DataAvailable = std::function<void()>;

  // `on_data_available` (optional) is called on a Cyclone thread when samples arrive (file comment).
  Reader(const Participant& participant, const Topic& topic, const QosConfig& qos,
         DataAvailable on_data_available = {})
      : callback_(std::make_unique<DataAvailable>(std::move(on_data_available))) {
    const QosPtr q = make_qos(qos);
    dds_listener_t* listener = nullptr;
    if (*callback_) {
      listener = dds_create_listener(callback_.get());
      dds_lset_data_available(listener, &Reader::on_data_available);
    }
    const dds_entity_t reader = dds_create_reader(participant.handle(), topic.handle(), q.get(), listener);
    if (listener != nullptr)
      dds_delete_listener(listener);
    entity_ = Entity(check_entity(reader, "creating the reader of " + topic.name()));
  }
  // The entity goes first: Cyclone waits for a running listener call before it deletes the reader,
  // so the callback outlives every call of it.
  ~Reader() { entity_.reset(); }
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  // Takes up to `max` samples (loaned, not copied) and calls fn(const T&, const dds_sample_info_t&)
  // for each valid one. Returns the number of valid samples.
  template <typename Fn>
  std::size_t take(std::size_t max, Fn&& fn) {
    constexpr std::size_t kBatch = 16;
    void* samples[kBatch] = {};
    dds_sample_info_t infos[kBatch];
    std::size_t valid = 0;
    while (max > 0) {
      const std::size_t want = max < kBatch ? max : kBatch;
      samples[0] = nullptr;  // loan from Cyclone
      const dds_return_t n = dds_take(entity_.handle(), samples, infos, want, static_cast<uint32_t>(want));
      check(n, "taking samples");
      if (n == 0)
        break;
      struct Loan {  // returned even if fn throws
        dds_entity_t reader;
        void** samples;
        dds_return_t n;
        ~Loan() { dds_return_loan(reader, samples, n); }
      } loan{entity_.handle(), samples, n};
      for (dds_return_t i = 0; i < n; ++i) {
        if (infos[i].valid_data) {
          ++valid;
          fn(*static_cast<const T*>(samples[i]), infos[i]);
        }
      }
      max -= static_cast<std::size_t>(n);
    }
    return valid;
  }

  // Writers currently matched (subscription_matched status).
  std::uint32_t matched_writers() const {
    dds_subscription_matched_status_t s{};
    check(dds_get_subscription_matched_status(entity_.handle(), &s), "reading the match status");
    return s.current_count;
  }
  dds_entity_t handle() const { return entity_.handle(); }

 private:
  static void on_data_available(dds_entity_t /*reader*/, void* arg) { (*static_cast<DataAvailable*>(arg))(); }

  std::unique_ptr<DataAvailable> callback_;
  Entity entity_;
};

// Writes samples of the C type T.
template <typename T>
class Writer {
 public:
  Writer(const Participant& participant, const Topic& topic, const QosConfig& qos)
      : topic_name_(topic.name()) {
    const QosPtr q = make_qos(qos);
    entity_ = Entity(check_entity(dds_create_writer(participant.handle(), topic.handle(), q.get(), nullptr),
                                  "creating the writer of " + topic.name()));
  }
  // Throws DdsError (e.g. Timeout when a reliable reader lags longer than max_blocking_s).
  void write(const T& sample) { check(dds_write(entity_.handle(), &sample), "writing to " + topic_name_); }
  // As write(), with an explicit source timestamp (ns since the epoch).
  void write(const T& sample, dds_time_t source_time) {
    check(dds_write_ts(entity_.handle(), &sample, source_time), "writing to " + topic_name_);
  }
  // Readers currently matched (publication_matched status).
  std::uint32_t matched_readers() const {
    dds_publication_matched_status_t s{};
    check(dds_get_publication_matched_status(entity_.handle(), &s), "reading the match status");
    return s.current_count;
  }
  dds_entity_t handle() const { return entity_.handle(); }

 private:
  std::string topic_name_;
  Entity entity_;
};

}  // namespace rsu::dds
