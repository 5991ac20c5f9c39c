// SPDX-License-Identifier: Apache-2.0
/* An independent ROS 2-style DDS participant for rsud's DDS test (tests/dds/dds_participant_test.py).
 * Plain C on Cyclone's C API and its own IDL (ros2_messages.idl); it includes nothing of the project.
 * Cyclone is configured the way a ROS 2 user does it: the CYCLONEDDS_URI environment variable.
 *
 * It publishes sensor_msgs/msg/PointCloud2 on --cloud-topic at --rate-hz for --seconds, cycling
 * through the cloud files given (prepared by the test driver, format below), stamped one rotation
 * (--rotation-s) before the moment of publication, as a LiDAR driver stamps a rotation with its start.
 * With --publish-poses FILE --pose-out-topic T it publishes geometry_msgs/msg/PoseWithCovarianceStamped
 * on T instead (no cloud files then): FILE has one pose a line, "<publish at, wall ns> <header stamp ns>
 * <frame_id> <x> <y> <z> <qx> <qy> <qz> <qw> <36 covariance values>", published in order, each not before
 * its time (rsu-autoware-sidecar's test: the RSU's fixes, and the vehicle's own poses).
 * Meanwhile it reads geometry_msgs/msg/PoseWithCovarianceStamped on --pose-topic and, with
 * --fixes-topic, rsud's object list (rsu_msgs/msg/VehicleFixArray, IDL from its .msg). It prints, flushed:
 *   published <index> <header stamp ns> <publication time ns>
 *   pose <receive time ns> <stamp ns> <frame_id> <x> <y> <z> <qx> <qy> <qz> <qw> <36 covariance values>
 *   fixes <receive time ns> <stamp ns> <frame_id> <rsu_id> <count> then per fix:
 *         <vehicle_id> <sweep time ns> <x> <y> <yaw variance> <points used>
 *   matched <cloud readers>
 * Cloud file (little endian): "PC2B", u32 width, u32 height, u32 point_step, u32 row_step,
 * u8 is_bigendian, u8 is_dense, u32 field count, per field {u8 name length, name, u32 offset,
 * u8 datatype, u32 count}, u32 data length, data.
 * Exit codes: 0 done, 1 a DDS call failed, 2 bad usage or file, 3 no reader matched within 10 s. */
#include <dds/dds.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ros2_messages.h"

#define MAX_CLOUDS 64
#define MAX_POSES 4096

typedef struct {
  uint32_t width, height, point_step, row_step;
  uint8_t is_bigendian, is_dense;
  uint32_t field_count;
  sensor_msgs_msg_dds__PointField_* fields;
  uint32_t data_length;
  uint8_t* data;
} cloud_file;

static int64_t wall_ns(void) {
  struct timespec ts;
  clock_gettime(CLOCK_REALTIME, &ts);
  return (int64_t)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

static void sleep_until(int64_t t_ns) {
  const int64_t now = wall_ns();
  if (t_ns <= now)
    return;
  struct timespec d = {(time_t)((t_ns - now) / 1000000000LL), (long)((t_ns - now) % 1000000000LL)};
  nanosleep(&d, NULL);
}

static int read_u32(FILE* f, uint32_t* v) {
  uint8_t b[4];
  if (fread(b, 1, 4, f) != 4)
    return 0;
  *v = (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) | ((uint32_t)b[3] << 24);
  return 1;
}

static int read_u8(FILE* f, uint8_t* v) {
  return fread(v, 1, 1, f) == 1;
}

static int load_cloud(const char* path, cloud_file* c) {
  FILE* f = fopen(path, "rb");
  char magic[4];
  int ok = f != NULL && fread(magic, 1, 4, f) == 4 && memcmp(magic, "PC2B", 4) == 0 &&
           read_u32(f, &c->width) && read_u32(f, &c->height) && read_u32(f, &c->point_step) &&
           read_u32(f, &c->row_step) && read_u8(f, &c->is_bigendian) && read_u8(f, &c->is_dense) &&
           read_u32(f, &c->field_count) && c->field_count < 64;
  if (ok) {
    c->fields = calloc(c->field_count, sizeof *c->fields);
    for (uint32_t i = 0; ok && i < c->field_count; ++i) {
      uint8_t n = 0;
      ok = read_u8(f, &n);
      c->fields[i].name = calloc((size_t)n + 1, 1);
      ok = ok && fread(c->fields[i].name, 1, n, f) == n && read_u32(f, &c->fields[i].offset) &&
           read_u8(f, &c->fields[i].datatype) && read_u32(f, &c->fields[i].count);
    }
  }
  ok = ok && read_u32(f, &c->data_length);
  if (ok) {
    c->data = malloc(c->data_length ? c->data_length : 1);
    ok = fread(c->data, 1, c->data_length, f) == c->data_length;
  }
  if (f != NULL)
    fclose(f);
  if (!ok)
    fprintf(stderr, "ros2_participant: cannot read cloud file %s\n", path);
  return ok;
}

typedef struct {
  int64_t publish_at, stamp;
  char frame_id[64];
  geometry_msgs_msg_dds__PoseWithCovariance_ pose;
} pose_line;

/* Reads up to MAX_POSES pose lines (format in the file comment); returns how many, -1 on a bad line. */
static int load_poses(const char* path, pose_line* poses) {
  FILE* f = fopen(path, "r");
  if (f == NULL) {
    fprintf(stderr, "ros2_participant: cannot open %s\n", path);
    return -1;
  }
  int n = 0;
  long long at, stamp;
  while (n < MAX_POSES && fscanf(f, "%lld %lld %63s", &at, &stamp, poses[n].frame_id) == 3) {
    geometry_msgs_msg_dds__PoseWithCovariance_* p = &poses[n].pose;
    int ok = fscanf(f, "%lf %lf %lf %lf %lf %lf %lf", &p->pose.position.x, &p->pose.position.y,
                    &p->pose.position.z, &p->pose.orientation.x, &p->pose.orientation.y,
                    &p->pose.orientation.z, &p->pose.orientation.w) == 7;
    for (int k = 0; ok && k < 36; ++k)
      ok = fscanf(f, "%lf", &p->covariance[k]) == 1;
    if (!ok) {
      fprintf(stderr, "ros2_participant: %s: bad pose line %d\n", path, n + 1);
      fclose(f);
      return -1;
    }
    poses[n].publish_at = at;
    poses[n].stamp = stamp;
    ++n;
  }
  fclose(f);
  return n;
}

static dds_qos_t* reliable_qos(void) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_MSECS(500));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 4);
  dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(q, 1, &xcdr1);
  return q;
}

static void check(dds_return_t rc, const char* what) {
  if (rc < 0) {
    fprintf(stderr, "ros2_participant: %s: %s\n", what, dds_strretcode(rc));
    exit(1);
  }
}

static int64_t stamp_ns(const builtin_interfaces_msg_dds__Time_* t) {
  return (int64_t)t->sec * 1000000000LL + t->nanosec;
}

static void print_pose(const void* sample, int64_t now) {
  const geometry_msgs_msg_dds__PoseWithCovarianceStamped_* m = sample;
  const geometry_msgs_msg_dds__Pose_* p = &m->pose.pose;
  printf("pose %lld %lld %s %.6f %.6f %.6f %.9f %.9f %.9f %.9f", (long long)now,
         (long long)stamp_ns(&m->header.stamp), m->header.frame_id[0] ? m->header.frame_id : "-",
         p->position.x, p->position.y, p->position.z, p->orientation.x, p->orientation.y, p->orientation.z,
         p->orientation.w);
  for (int k = 0; k < 36; ++k)
    printf(" %.9g", m->pose.covariance[k]);
  printf("\n");
}

static void print_fix_list(const void* sample, int64_t now) {
  const rsu_msgs_msg_dds__VehicleFixArray_* m = sample;
  printf("fixes %lld %lld %s %llu %u", (long long)now, (long long)stamp_ns(&m->header.stamp),
         m->header.frame_id[0] ? m->header.frame_id : "-", (unsigned long long)m->rsu_id, m->fixes._length);
  for (uint32_t k = 0; k < m->fixes._length; ++k) {
    const rsu_msgs_msg_dds__VehicleFix_* f = &m->fixes._buffer[k];
    printf(" %llu %lld %.6f %.6f %.9g %u", (unsigned long long)f->vehicle_id,
           (long long)stamp_ns(&f->sweep_time), f->pose.pose.position.x, f->pose.pose.position.y,
           f->pose.covariance[35], f->points_used);
  }
  printf("\n");
}

/* Takes every sample waiting on `reader` and prints each valid one with `print`. */
static void print_all(dds_entity_t reader, void (*print)(const void*, int64_t)) {
  void* samples[8] = {NULL};
  dds_sample_info_t infos[8];
  for (;;) {
    samples[0] = NULL;
    const dds_return_t n = dds_take(reader, samples, infos, 8, 8);
    check(n, "taking samples");
    if (n == 0)
      return;
    const int64_t now = wall_ns();
    for (int i = 0; i < n; ++i)
      if (infos[i].valid_data)
        print(samples[i], now);
    dds_return_loan(reader, samples, n);
    fflush(stdout);
  }
}

/* A participant on `domain` (-1: Cyclone's default domain, 0 or what CYCLONEDDS_URI says). */
static dds_entity_t create_participant(int domain) {
  const dds_entity_t participant =
      dds_create_participant(domain < 0 ? DDS_DOMAIN_DEFAULT : (dds_domainid_t)domain, NULL, NULL);
  check(participant, "creating the participant");
  return participant;
}

/* A reader of PoseWithCovarianceStamped on `topic`, or 0 when `topic` is NULL. */
static dds_entity_t create_pose_reader(dds_entity_t participant, const char* topic, const dds_qos_t* qos) {
  if (topic == NULL)
    return 0;
  const dds_entity_t t = dds_create_topic(
      participant, &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, topic, NULL, NULL);
  check(t, "creating the pose topic");
  const dds_entity_t reader = dds_create_reader(participant, t, qos, NULL);
  check(reader, "creating the pose reader");
  return reader;
}

/* Waits (bounded, 10 s) until `writer` has a matched reader; prints "matched <count>". */
static uint32_t wait_for_reader(dds_entity_t writer) {
  dds_publication_matched_status_t matched = {0};
  const int64_t match_deadline = wall_ns() + 10000000000LL;
  while (matched.current_count == 0 && wall_ns() < match_deadline) {
    check(dds_get_publication_matched_status(writer, &matched), "reading the match status");
    if (matched.current_count == 0)
      sleep_until(wall_ns() + 10000000LL);
  }
  printf("matched %u\n", matched.current_count);
  fflush(stdout);
  return matched.current_count;
}

/* --publish-poses: the poses of `path` on `out_topic`, printing what arrives on `in_topic` meanwhile. */
static int publish_poses(const char* path, const char* out_topic, const char* in_topic, int domain,
                         double linger_s) {
  static pose_line poses[MAX_POSES];
  const int count = load_poses(path, poses);
  if (count <= 0)
    return 2;
  const dds_entity_t participant = create_participant(domain);
  dds_qos_t* qos = reliable_qos();
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 64);
  const dds_entity_t ot = dds_create_topic(
      participant, &geometry_msgs_msg_dds__PoseWithCovarianceStamped__desc, out_topic, NULL, NULL);
  check(ot, "creating the pose output topic");
  const dds_entity_t writer = dds_create_writer(participant, ot, qos, NULL);
  check(writer, "creating the pose writer");
  const dds_entity_t reader = create_pose_reader(participant, in_topic, qos);
  dds_delete_qos(qos);
  if (wait_for_reader(writer) == 0) {
    dds_delete(participant);
    return 3;
  }
  for (int i = 0; i < count; ++i) {
    sleep_until(poses[i].publish_at);
    geometry_msgs_msg_dds__PoseWithCovarianceStamped_ msg;
    memset(&msg, 0, sizeof msg);
    msg.header.stamp.sec = (int32_t)(poses[i].stamp / 1000000000LL);
    msg.header.stamp.nanosec = (uint32_t)(poses[i].stamp % 1000000000LL);
    msg.header.frame_id = poses[i].frame_id;
    msg.pose = poses[i].pose;
    check(dds_write(writer, &msg), "writing a pose");
    printf("published %d %lld %lld\n", i, (long long)poses[i].stamp, (long long)wall_ns());
    fflush(stdout);
    if (reader)
      print_all(reader, print_pose);
  }
  const int64_t linger_end = wall_ns() + (int64_t)(linger_s * 1e9);
  while (reader && wall_ns() < linger_end) {
    print_all(reader, print_pose);
    sleep_until(wall_ns() + 10000000LL);
  }
  dds_delete(participant);
  return 0;
}

int main(int argc, char** argv) {
  const char *cloud_topic = "rt/points", *pose_topic = NULL, *fixes_topic = NULL, *frame_id = "lidar";
  const char *poses_file = NULL, *pose_out_topic = NULL;
  int domain = -1; /* -1: Cyclone's default domain (0, or what CYCLONEDDS_URI says) */
  double rate_hz = 10.0, seconds = 3.0, rotation_s = 0.1, linger_s = 1.0;
  const char* files[MAX_CLOUDS];
  int nfiles = 0;
  for (int i = 1; i < argc; ++i) {
    const int more = i + 1 < argc;
    if (!strcmp(argv[i], "--cloud-topic") && more)
      cloud_topic = argv[++i];
    else if (!strcmp(argv[i], "--pose-topic") && more)
      pose_topic = argv[++i];
    else if (!strcmp(argv[i], "--fixes-topic") && more)
      fixes_topic = argv[++i];
    else if (!strcmp(argv[i], "--publish-poses") && more)
      poses_file = argv[++i];
    else if (!strcmp(argv[i], "--pose-out-topic") && more)
      pose_out_topic = argv[++i];
    else if (!strcmp(argv[i], "--frame-id") && more)
      frame_id = argv[++i];
    else if (!strcmp(argv[i], "--domain") && more)
      domain = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--rate-hz") && more)
      rate_hz = atof(argv[++i]);
    else if (!strcmp(argv[i], "--seconds") && more)
      seconds = atof(argv[++i]);
    else if (!strcmp(argv[i], "--rotation-s") && more)
      rotation_s = atof(argv[++i]);
    else if (!strcmp(argv[i], "--linger-s") && more)
      linger_s = atof(argv[++i]);
    else if (argv[i][0] != '-' && nfiles < MAX_CLOUDS)
      files[nfiles++] = argv[i];
    else {
      fprintf(stderr,
              "usage: ros2_participant [--domain N] [--cloud-topic rt/points] [--pose-topic rt/...] "
              "[--frame-id lidar] [--publish-poses FILE --pose-out-topic rt/...] "
              "[--rate-hz 10] [--seconds 3] [--rotation-s 0.1] [--linger-s 1] CLOUD_FILE...\n");
      return 2;
    }
  }
  if ((poses_file == NULL) != (pose_out_topic == NULL)) {
    fprintf(stderr, "ros2_participant: --publish-poses and --pose-out-topic go together\n");
    return 2;
  }
  if (poses_file != NULL)
    return publish_poses(poses_file, pose_out_topic, pose_topic, domain, linger_s);
  if (nfiles == 0 || !(rate_hz > 0 && rate_hz <= 100) || !(seconds > 0 && seconds <= 600)) {
    fprintf(stderr, "ros2_participant: need cloud files, 0 < rate <= 100 Hz, 0 < seconds <= 600\n");
    return 2;
  }
  cloud_file clouds[MAX_CLOUDS];
  memset(clouds, 0, sizeof clouds);
  for (int i = 0; i < nfiles; ++i)
    if (!load_cloud(files[i], &clouds[i]))
      return 2;

  const dds_entity_t participant = create_participant(domain);
  dds_qos_t* qos = reliable_qos();
  const dds_entity_t ct =
      dds_create_topic(participant, &sensor_msgs_msg_dds__PointCloud2__desc, cloud_topic, NULL, NULL);
  check(ct, "creating the cloud topic");
  const dds_entity_t writer = dds_create_writer(participant, ct, qos, NULL);
  check(writer, "creating the cloud writer");
  const dds_entity_t pose_reader = create_pose_reader(participant, pose_topic, qos);
  dds_entity_t fixes_reader = 0;
  if (fixes_topic != NULL) {
    const dds_entity_t ft =
        dds_create_topic(participant, &rsu_msgs_msg_dds__VehicleFixArray__desc, fixes_topic, NULL, NULL);
    check(ft, "creating the object list topic");
    fixes_reader = dds_create_reader(participant, ft, qos, NULL);
    check(fixes_reader, "creating the object list reader");
  }
  dds_delete_qos(qos);

  /* Discovery is asynchronous: wait (bounded) until the cloud reader is matched. */
  if (wait_for_reader(writer) == 0) {
    dds_delete(participant);
    return 3;
  }

  const int64_t period = (int64_t)(1e9 / rate_hz), start = wall_ns();
  const int64_t total = (int64_t)(seconds * rate_hz);
  for (int64_t i = 0; i < total; ++i) {
    sleep_until(start + i * period);
    const cloud_file* c = &clouds[i % nfiles];
    sensor_msgs_msg_dds__PointCloud2_ msg;
    memset(&msg, 0, sizeof msg);
    const int64_t published = wall_ns();
    const int64_t stamp = published - (int64_t)(rotation_s * 1e9);
    msg.header.stamp.sec = (int32_t)(stamp / 1000000000LL);
    msg.header.stamp.nanosec = (uint32_t)(stamp % 1000000000LL);
    msg.header.frame_id = (char*)frame_id;
    msg.height = c->height;
    msg.width = c->width;
    msg.fields._buffer = c->fields;
    msg.fields._length = msg.fields._maximum = c->field_count;
    msg.is_bigendian = c->is_bigendian;
    msg.point_step = c->point_step;
    msg.row_step = c->row_step;
    msg.data._buffer = c->data;
    msg.data._length = msg.data._maximum = c->data_length;
    msg.is_dense = c->is_dense;
    check(dds_write_ts(writer, &msg, published), "writing a cloud");
    printf("published %lld %lld %lld\n", (long long)i, (long long)stamp, (long long)published);
    fflush(stdout);
    if (pose_reader)
      print_all(pose_reader, print_pose);
    if (fixes_reader)
      print_all(fixes_reader, print_fix_list);
  }
  const int64_t linger_end = wall_ns() + (int64_t)(linger_s * 1e9);
  while ((pose_reader || fixes_reader) && wall_ns() < linger_end) {
    if (pose_reader)
      print_all(pose_reader, print_pose);
    if (fixes_reader)
      print_all(fixes_reader, print_fix_list);
    sleep_until(wall_ns() + 10000000LL);
  }
  for (int i = 0; i < nfiles; ++i) {
    for (uint32_t k = 0; k < clouds[i].field_count; ++k)
      free(clouds[i].fields[k].name);
    free(clouds[i].fields);
    free(clouds[i].data);
  }
  dds_delete(participant);
  return 0;
}
