// The type a writer's topic serializes with: Cyclone's own CDR (XCDR1, the same bytes, keys, key
// hashes and type information as dds_create_topic's), with one change: each sample's buffer is
// allocated at its size instead of being taken from the domain's pool of freed sample buffers.
//
// Why: Cyclone 0.10.2's dds_write serializes into a buffer popped from a per-domain pool of freed
// samples of any size up to 256 B (ddsi_serdata_default.c, serdata_default_new), assuming it holds at
// least 128 B; the pool also gets the buffers of *received* samples, so a 60-byte raw hand sample freed
// by the filter's thread can be handed to its next stroke (80 bytes), whose output stream grows it by
// a 4 KiB step (ddsi_cdrstream.c, dds_ostream_grow). A transient-local writer keeps such buffers in its
// history: in tachi-filter (heaptrack, 3.5 minutes of a looped recording) 836 stroke writes grew one,
// 754 KB of its 977 KB heap peak, and how many of the 256 kept strokes were 4 KiB ones changed with
// the pool's per-thread magazines, so its resident memory wandered by up to 1 MB in the one-hour soak
// (docs/benchmarks.md, "Soak"). Cyclone's master dropped the pool; bookworm has 0.10.2.
//
// How: the sertype has the layout of Cyclone's default one (ddsi_serdata_default.h, installed with
// 0.10.2) and reuses its sertype operations and every serdata operation that does not allocate
// (sizes, keys, key hashes, to-CDR, to-sample, printing); the serdata operations that allocate are
// ours. The pipeline's readers never use this type (they keep dds_create_topic's), so the receive
// paths (from a fragment chain, from a key hash) refuse; a local reader of it gets the written samples
// themselves (local delivery shares them), which is how the test looks at their buffers.
#include "tachi/bus/bus.hpp"

#include <dds/ddsi/ddsi_cdrstream.h>
#include <dds/ddsi/ddsi_serdata_default.h>
#include <dds/ddsi/ddsi_sertype.h>
#include <dds/ddsrt/heap.h>
#include <dds/ddsrt/mh3.h>
#include <dds/ddsrt/string.h>
#include <dds/version.h>

#include <algorithm>
#include <cstddef>
#include <cstring>
#include <string>

namespace tachi::bus::detail {
namespace {

static_assert(DDS_VERSION_MAJOR == 0 && DDS_VERSION_MINOR == 10,
              "writer_sertype.cpp relies on Cyclone DDS 0.10's ddsi_serdata_default layout");

using SertypeDefault = ddsi_sertype_default;
using SerdataDefault = ddsi_serdata_default;

const SertypeDefault& sertype_of(const ddsi_serdata* d) { return *reinterpret_cast<const SertypeDefault*>(d->type); }

// A serdata's fields before its CDR: a serialization stream starts there, as Cyclone's does
// (dds_ostream_from_serdata_default), so the CDR's alignment is the same.
constexpr std::uint32_t kHeader = offsetof(SerdataDefault, data);
static_assert(kHeader % 8 == 0, "the CDR of a serdata starts 8-byte aligned");

// Initializes the fields before the CDR in `memory`, an allocation of kHeader + `capacity` bytes.
SerdataDefault* init_header(void* memory, const ddsi_sertype* type, ddsi_serdata_kind kind, std::uint32_t capacity) {
  auto* d = static_cast<SerdataDefault*>(memory);
  std::memset(memory, 0, kHeader);
  ddsi_serdata_init(&d->c, type, kind);
  d->size = capacity;
  d->serpool = nullptr;  // never pooled: free_serdata gives it back to the heap
  return d;
}

// A stream a thread serializes into, kept between samples so that a small write allocates only its
// sample. `start` bytes are left free at its front (a serdata's header, for the payload stream).
struct ReusedStream {
  dds_ostream_t stream{};
  ReusedStream() = default;
  ReusedStream(const ReusedStream&) = delete;
  ReusedStream& operator=(const ReusedStream&) = delete;
  ~ReusedStream() { dds_ostream_fini(&stream); }
  dds_ostream_t& reset(std::uint32_t xcdr_version, std::uint32_t start) {
    if (stream.m_size < start + 256) {
      stream.m_buffer = static_cast<unsigned char*>(ddsrt_realloc(stream.m_buffer, 4096));
      stream.m_size = 4096;
    }
    stream.m_index = start;
    stream.m_xcdr_version = xcdr_version;
    return stream;
  }
};
thread_local ReusedStream t_payload;
thread_local ReusedStream t_key;

// Up to this size a sample is copied out of the thread's stream into an allocation of its size; a
// larger one takes the stream's buffer itself, shrunk to it (realloc), and the next write starts a new
// one: a copy of a 196 KB cloth state would cost more than the buffer's regrowth.
constexpr std::uint32_t kCopyUpTo = 4096;

// The serdata for the payload in t_payload (after kHeader) and the XCDR2 key in `key_stream`, sized
// to them, its hash computed as Cyclone's serdata's is.
ddsi_serdata* build(const ddsi_sertype* type, ddsi_serdata_kind kind, std::uint32_t xcdr_version,
                    const dds_ostream_t* key_stream) {
  const auto& tp = *reinterpret_cast<const SertypeDefault*>(type);
  dds_ostream_t& payload = t_payload.stream;
  const std::uint32_t length = payload.m_index - kHeader;
  const std::uint32_t padded = (length + 3u) & ~3u;  // DDSI wants 4-byte multiples; the pad is in options
  const std::uint32_t key_size = key_stream != nullptr ? key_stream->m_index : 0;
  const std::size_t total = std::size_t{kHeader} + padded + key_size;
  void* memory = nullptr;
  if (total <= kCopyUpTo) {
    memory = ddsrt_malloc(total);
    std::memcpy(static_cast<unsigned char*>(memory) + kHeader, payload.m_buffer + kHeader, length);
  } else {
    memory = ddsrt_realloc(payload.m_buffer, total);
    payload.m_buffer = nullptr;
    payload.m_size = 0;
  }
  SerdataDefault* d = init_header(memory, type, kind, padded);
  std::memset(d->data + length, 0, padded - length);
  d->pos = padded;
  d->hdr.identifier = ddsi_sertype_get_native_enc_identifier(xcdr_version, tp.encoding_format);
  d->hdr.options = ddsrt_toBE2u(static_cast<uint16_t>(padded - length));
  d->key.buftype = KEYBUFTYPE_DYNALIAS;  // into this allocation: freed with it
  d->key.keysize = key_size & SERDATA_DEFAULT_KEYSIZE_MASK;
  d->key.u.dynbuf = reinterpret_cast<unsigned char*>(d->data) + padded;
  if (key_size > 0) std::memcpy(d->key.u.dynbuf, key_stream->m_buffer, key_size);
  d->c.hash = tp.type.keys.nkeys == 0 ? type->serdata_basehash
                                      : ddsrt_mh3(d->key.u.dynbuf, key_size, type->serdata_basehash);
  return &d->c;
}

ddsi_serdata* from_sample(const ddsi_sertype* type, ddsi_serdata_kind kind, const void* sample) {
  const auto& tp = *reinterpret_cast<const SertypeDefault*>(type);
  const std::uint32_t xcdr_version = tp.write_encoding_version;
  dds_ostream_t& payload = t_payload.reset(xcdr_version, kHeader);
  switch (kind) {
    case SDK_EMPTY: break;
    case SDK_KEY: dds_stream_write_key(&payload, static_cast<const char*>(sample), &tp); break;
    case SDK_DATA:
      if (!dds_stream_write_sample(&payload, sample, &tp)) return nullptr;
      break;
  }
  if (kind == SDK_EMPTY || tp.type.keys.nkeys == 0) return build(type, kind, xcdr_version, nullptr);
  dds_ostream_t& key = t_key.reset(CDR_ENC_VERSION_2, 0);
  // The key as Cyclone keeps it in a serdata: XCDR2, native byte order (gen_serdata_key).
  dds_stream_write_key(&key, static_cast<const char*>(sample), &tp);
  return build(type, kind, xcdr_version, &key);
}

// The untyped key a writer keeps per instance (serdata_default_to_untyped): the XCDR2 key as an
// SDK_KEY serdata of no type.
ddsi_serdata* to_untyped(const ddsi_serdata* serdata) {
  const auto* d = reinterpret_cast<const SerdataDefault*>(serdata);
  const std::uint32_t key_size = d->key.keysize;
  const std::uint32_t padded = (key_size + 3u) & ~3u;
  SerdataDefault* u = init_header(ddsrt_malloc(kHeader + padded), serdata->type, SDK_KEY, padded);
  u->c.type = nullptr;
  u->c.hash = serdata->hash;
  u->c.timestamp.v = INT64_MIN;
  const unsigned char* key = d->key.buftype == KEYBUFTYPE_STATIC ? d->key.u.stbuf : d->key.u.dynbuf;
  if (key_size > 0) std::memcpy(u->data, key, key_size);
  std::memset(u->data + key_size, 0, padded - key_size);
  u->pos = key_size;
  u->hdr.identifier = ddsi_sertype_get_native_enc_identifier(CDR_ENC_VERSION_2, sertype_of(serdata).encoding_format);
  u->key.buftype = KEYBUFTYPE_DYNALIAS;
  u->key.keysize = key_size & SERDATA_DEFAULT_KEYSIZE_MASK;
  u->key.u.dynbuf = reinterpret_cast<unsigned char*>(u->data);
  return &u->c;
}

// Received data and key hashes go to readers, which use dds_create_topic's type; nothing converts
// into a writer's type (tachi play writes samples, not CDR).
ddsi_serdata* from_ser(const ddsi_sertype*, ddsi_serdata_kind, const nn_rdata*, std::size_t) { return nullptr; }
ddsi_serdata* from_ser_iov(const ddsi_sertype*, ddsi_serdata_kind, ddsrt_msg_iovlen_t, const ddsrt_iovec_t*,
                           std::size_t) {
  return nullptr;
}
ddsi_serdata* from_keyhash(const ddsi_sertype*, const ddsi_keyhash*) { return nullptr; }

void free_serdata(ddsi_serdata* serdata) { ddsrt_free(serdata); }  // key aliases into it

// Cyclone's serdata operations (keyed or keyless) with the allocating ones replaced.
ddsi_serdata_ops with_exact_allocation(ddsi_serdata_ops ops) {
  ops.from_ser = from_ser;
  ops.from_ser_iov = from_ser_iov;
  ops.from_keyhash = from_keyhash;
  ops.from_sample = from_sample;
  ops.to_untyped = to_untyped;
  ops.free = free_serdata;
#ifdef DDS_HAS_SHM
  ops.get_sample_size = nullptr;  // no iceoryx: tachi's writers never loan shared-memory samples
  ops.from_iox_buffer = nullptr;
#endif
  return ops;
}

const ddsi_serdata_ops& serdata_ops(bool keyed) {
  static const ddsi_serdata_ops keyed_ops = with_exact_allocation(ddsi_serdata_ops_cdr);
  static const ddsi_serdata_ops keyless_ops = with_exact_allocation(ddsi_serdata_ops_cdr_nokey);
  return keyed ? keyed_ops : keyless_ops;
}

// Cyclone's default sertype operations at an address of our own, so that dds_create_topic_sertype
// does not find this type equal to (and replace it with) dds_create_topic's.
const ddsi_sertype_ops& sertype_ops() {
  static const ddsi_sertype_ops ops = [] {
    ddsi_sertype_ops o = ddsi_sertype_ops_default;
    o.derive_sertype = nullptr;  // the writer uses this type as it is: XCDR1
    return o;
  }();
  return ops;
}

}  // namespace

dds_entity_t create_writer_topic(const Participant& participant, const dds_topic_descriptor_t* descriptor,
                                 const char* name) {
  const std::string what = std::string("create topic ") + name + " for a writer";
  ddsi_sertype_extensibility extensibility{};
  if (!dds_stream_extensibility(descriptor->m_ops, &extensibility))
    throw DdsError(what + ": the type's serializer ops have no extensibility", DDS_RETCODE_BAD_PARAMETER);
  if (dds_stream_minimum_xcdr_version(descriptor->m_ops) != CDR_ENC_VERSION_1)
    throw DdsError(what + ": the type needs XCDR2, which the writer type does not write", DDS_RETCODE_UNSUPPORTED);
  // Filled as ddsi_sertype_default_init fills it (ddsi_sertype_default.c), with ddsrt's allocator,
  // because the default sertype operations free it with ddsrt_free.
  auto* st = static_cast<SertypeDefault*>(ddsrt_malloc(sizeof(SertypeDefault)));
  std::memset(static_cast<void*>(st), 0, sizeof *st);
  const bool keyed = descriptor->m_nkeys > 0;
  ddsi_sertype_init(&st->c, descriptor->m_typename, &sertype_ops(), &serdata_ops(keyed), !keyed);
  st->c.fixed_size = (st->c.fixed_size || (descriptor->m_flagset & DDS_TOPIC_FIXED_SIZE)) ? 1u : 0u;
  // As dds_create_topic's type allows (so the topic's QoS, XCDR1 and XCDR2, equals the one a reader's
  // dds_create_topic gives the same topic in this participant); a writer of ours asks for no data
  // representation and gets XCDR1, the one this type writes.
  st->c.allowed_data_representation = (descriptor->m_flagset & DDS_TOPIC_RESTRICT_DATA_REPRESENTATION) != 0
                                          ? descriptor->restrict_data_representation
                                          : DDS_DATA_REPRESENTATION_RESTRICT_DEFAULT;
  st->encoding_format = ddsi_sertype_extensibility_enc_format(extensibility);
  st->write_encoding_version = CDR_ENC_VERSION_1;
  st->serpool = nullptr;
  st->type.size = descriptor->m_size;
  st->type.align = descriptor->m_align;
  st->type.flagset = descriptor->m_flagset;
  st->type.keys.nkeys = descriptor->m_nkeys;
  st->type.keys.keys = static_cast<ddsi_sertype_default_desc_key_t*>(
      ddsrt_malloc(std::max<std::size_t>(1, descriptor->m_nkeys) * sizeof(ddsi_sertype_default_desc_key_t)));
  for (std::uint32_t i = 0; i < descriptor->m_nkeys; ++i) {
    st->type.keys.keys[i].ops_offs = descriptor->m_keys[i].m_offset;
    st->type.keys.keys[i].idx = descriptor->m_keys[i].m_idx;
  }
  st->type.ops.nops = dds_stream_countops(descriptor->m_ops, descriptor->m_nkeys, descriptor->m_keys);
  st->type.ops.ops =
      static_cast<std::uint32_t*>(ddsrt_memdup(descriptor->m_ops, st->type.ops.nops * sizeof(std::uint32_t)));
  if ((descriptor->m_flagset & DDS_TOPIC_XTYPES_METADATA) != 0 && descriptor->type_information.sz > 0 &&
      descriptor->type_mapping.sz > 0) {
    // The type information discovery carries, so readers match this writer by type as they match
    // dds_create_topic's writers.
    st->type.typeinfo_ser.sz = descriptor->type_information.sz;
    st->type.typeinfo_ser.data =
        static_cast<std::uint8_t*>(ddsrt_memdup(descriptor->type_information.data, descriptor->type_information.sz));
    st->type.typemap_ser.sz = descriptor->type_mapping.sz;
    st->type.typemap_ser.data =
        static_cast<std::uint8_t*>(ddsrt_memdup(descriptor->type_mapping.data, descriptor->type_mapping.sz));
  }
  st->opt_size_xcdr1 = dds_stream_check_optimize(&st->type, CDR_ENC_VERSION_1);
  st->opt_size_xcdr2 = dds_stream_check_optimize(&st->type, CDR_ENC_VERSION_2);
  ddsi_sertype* sertype = &st->c;
  const dds_entity_t topic = dds_create_topic_sertype(participant.handle(), name, &sertype, nullptr, nullptr, nullptr);
  if (topic < 0) ddsi_sertype_unref(&st->c);  // not handed over: ours to free
  return check(topic, what + ": dds_create_topic_sertype");
}

}  // namespace tachi::bus::detail
