// SPDX-License-Identifier: MIT
// The ballbar database: sessions with their audit trail, raw samples, points, results and identified
// models, in one SQLite file (WAL mode). See docs/storage.md for the schema and the guarantees.
//
//   Store store(path);                                  // creates/migrates; marks crashed sessions interrupted
//   auto id = store.create_session({...});              // state `created`
//   store.start_session(id);                            // `running`; this Store now owns the session
//   SampleWriter writer(store, id);  writer.append(s);  // batched commits (sample_writer.hpp)
//   store.add_point(id, point);  store.finish_session(id);
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/analysis/reading.hpp"
#include "ballbar/analysis/sample.hpp"
#include "ballbar/analysis/types.hpp"
#include "ballbar/storage/sqlite.hpp"

namespace ballbar::storage {

/// Where a session's samples came from.
enum class SessionSource { device, emulator, imported };
std::string_view to_string(SessionSource source);
std::optional<SessionSource> parse_session_source(std::string_view text);

/// Lifecycle of a session. `created` → `running` → `completed` | `aborted` | `failed`; a session found
/// unfinished (created/running) with no live owner when a Store opens becomes `interrupted`, from which it
/// can be resumed (→ `running`), completed with what it has, or aborted. A `failed` session can be
/// resumed too (→ `running`): what it measured stays and the procedure continues after it.
enum class SessionState { created, running, completed, aborted, failed, interrupted };
std::string_view to_string(SessionState state);
std::optional<SessionState> parse_session_state(std::string_view text);
/// Whether `from` → `to` is a legal transition.
bool transition_allowed(SessionState from, SessionState to);

/// The instrument (bar) a session was measured with. Keys of the readings file's `instrument` header.
struct Instrument {
    std::string model;
    std::string serial;
    std::string firmware;
    std::optional<double> calibrated_length_mm;
    std::string calibration_date;  ///< ISO 8601 date, empty when unknown
    std::string extra_json;        ///< other keys of the `instrument` header, as a JSON object ("" = none)
};

/// A machine of the registry (`ballbar machines`), or one known only by the geometry a session was
/// measured with (no asset id). Schema v7.
struct MachineEntry {
    std::int64_t id = 0;
    std::string uuid;
    std::string asset_id;  ///< the shop's id for it, unique; empty: not registered
    std::string name;
    analysis::MachineType type = analysis::MachineType::TTTRR;
    std::string geometry_json;
    std::string location;           ///< hall, cell: free text
    std::string machine_file_json;  ///< registered: its whole machine file (travel, dialect, feed, tolerances)
    std::string registered_at;      ///< ISO 8601; empty: not registered
    std::string updated_at;         ///< last `edit`; empty: never edited
    std::int64_t session_count = 0;
};

/// A machine to register.
struct NewMachine {
    std::string asset_id;
    std::string name;
    std::string location;
    analysis::MachineGeometry geometry;
    std::string machine_file_json;
};

/// What `machines edit` changes (empty: kept). The geometry only while no session was measured on it.
struct MachineEdit {
    std::optional<std::string> name;
    std::optional<std::string> location;
    std::optional<analysis::MachineGeometry> geometry;
    std::optional<std::string> machine_file_json;
};

/// What the caller knows when a session begins.
struct NewSession {
    analysis::MachineGeometry machine;
    /// The registry's machine measured (its asset id); `machine` must be its geometry. Empty: the
    /// session's machine is known by its geometry only.
    std::string machine_asset;
    std::optional<Instrument> instrument;
    SessionSource source = SessionSource::device;
    std::string operator_name;
    std::string procedure;  ///< e.g. "ssm" or a plan name; free text
    std::string notes;
    std::string started_at;     ///< ISO 8601; empty: now (the Store's clock)
    std::string metadata_json;  ///< other metadata as a JSON object, e.g. unknown readings-file header keys
};

/// A stored session as read back.
struct SessionInfo {
    std::int64_t id = 0;
    std::string uuid;
    analysis::MachineGeometry machine;
    std::string machine_asset;  ///< the registry's asset id; empty: not registered (or a file before v7)
    std::optional<Instrument> instrument;
    SessionSource source = SessionSource::device;
    SessionState state = SessionState::created;
    std::string operator_name;
    std::string procedure;
    std::string notes;
    std::string started_at;
    std::optional<std::string> ended_at;
    std::string metadata_json;
    std::int64_t sample_count = 0;
    std::int64_t point_count = 0;
    /// Why it is in its state: the event of the transition into it ("fail: no samples for 30 s",
    /// "interrupted: found unfinished on open", …), or, for a session stored as created/running whose
    /// writer is gone (killed, crashed), "interrupted: its writer is gone" — `state` is then
    /// `interrupted` for every reader, even one that does not write (recover = false, read_only).
    std::string reason;
    bool writer_gone = false;  ///< stored as created/running, but no live process holds its lock
    /// interrupted or failed: `ballbar measure --resume` continues it.
    bool resumable() const { return state == SessionState::interrupted || state == SessionState::failed; }
};

/// A run of a session's samples on one device clock: a connection, or the same one after a resume. The
/// writer records one when it starts and whenever the device clock goes back (a replug that restarted
/// the instrument); SessionClock (session_clock.hpp) turns them into one monotonic session time.
struct SampleSegment {
    std::uint64_t first_seq = 0;
    std::uint64_t device_time_us = 0;  ///< of its first sample
    std::string started_at;            ///< the Store's clock when the writer took that sample (ISO 8601)
    /// The instrument over this segment's samples (schema v4; empty: not known): its resolution (the
    /// finest step it reports) and the reading rate actually measured.
    std::optional<double> resolution_mm;
    std::optional<double> reading_rate_hz;
};

/// A gap in a session's stream: samples the instrument sent and the host lost (the driver saw the
/// sequence numbers jump), or a stream that came back after a reconnect without them. Recorded by the
/// SampleWriter (schema v6); the sample after it carries kSampleAfterGap.
struct SampleGap {
    std::uint64_t before_seq = 0;      ///< stored seq of the first sample after the gap
    std::optional<double> duration_s;  ///< instrument time between the samples either side; empty: the
                                       ///< instrument's clock restarted (a reconnect)
    std::string cause;                 ///< "lost frames" or "reconnect"
};

/// One entry of a session's audit trail.
struct Transition {
    std::optional<SessionState> from;  ///< empty for the creation entry
    SessionState to = SessionState::created;
    std::string event;  ///< why: "create", "start", "finish", "abort", "fail: …", "interrupted", "resume", …
    std::string at;     ///< ISO 8601 UTC
};

/// A step of the guided procedure (acquisition's state machine: "Step1Capture", "Computing", …),
/// kept next to the session's lifecycle in the transitions table (scope "procedure").
struct ProcedureStep {
    std::string from;  ///< state names of the procedure, not SessionState
    std::string to;
    std::string event;   ///< "InPosition", "PointAccepted", "DeviceLost", …
    std::string detail;  ///< "test 2 step 1 point 3: 99.98 mm, std 0.1 µm, n 500", …
    std::string at;      ///< ISO 8601 UTC; the store's clock when added with it empty
};

/// One averaged reading of a session, with where it came from.
struct PointRecord {
    std::int64_t index = -1;  ///< order within the session (assigned by add_point)
    analysis::Reading reading;
    double nominal_mm = 0;                             ///< nominal bar length |b − s| at the commanded pose
    std::optional<std::uint64_t> first_seq, last_seq;  ///< sample window averaged into the reading
};

/// A typed analysis result (SSM ΔV, orientation, identification, discovery, …).
struct ResultRecord {
    std::int64_t id = 0;
    std::int64_t session_id = 0;
    std::string kind;                      ///< e.g. "ssm", "identification", "discovery"
    std::string payload_json;              ///< the result itself, a JSON document
    std::optional<std::int64_t> model_id;  ///< the model version that produced it (models table), if any
    std::string producer;                  ///< software/algorithm version, e.g. "ballbar 0.1.0 ssm/2"
    std::string created_at;
};

/// One version of an identified parameter set. Versions of a name count 1, 2, …
struct ModelRecord {
    std::int64_t id = 0;
    std::string name;
    int version = 0;
    std::optional<std::int64_t> parent_id;  ///< the version this one was refined from
    std::string params_json;
    std::string notes;
    std::string created_at;
    std::vector<std::int64_t> session_ids;  ///< sessions whose data identified it
};

struct StoreOptions {
    /// Wall clock for audit times. Default: std::chrono::system_clock::now.
    std::function<std::chrono::system_clock::time_point()> clock;
    int busy_timeout_ms = 5000;
    /// Mark unfinished sessions whose owner is gone as `interrupted` on open (needs write access).
    bool recover = true;
    /// Open read-only (no migrations, no recovery). The file must exist.
    bool read_only = false;
    /// PRAGMA synchronous: true = FULL (each commit survives power loss), false = NORMAL (survives a
    /// killed process; the last commits may be lost on power loss).
    bool sync_full = true;
};

class Store {
  public:
    static constexpr int kSchemaVersion = 7;
    static constexpr std::int64_t kApplicationId = 0x42424152;  // "BBAR"

    /// Opens or creates the database at `path` and migrates it to kSchemaVersion. Throws StorageError:
    /// Kind::corrupt for a file that is not a (complete) SQLite database, Kind::newer_schema for one
    /// written by a newer ballbar — in both cases the file is left exactly as it was.
    explicit Store(const std::string& path, StoreOptions options = {});
    ~Store();
    Store(const Store&) = delete;
    Store& operator=(const Store&) = delete;

    Database& db() { return db_; }
    const std::string& path() const { return db_.path(); }
    /// Sessions this open marked `interrupted`.
    const std::vector<std::int64_t>& recovered_sessions() const { return recovered_; }
    /// For an open that only reads (no recovery, or read-only): "" when the file passes SQLite's quick
    /// check, else what fails it (the message that refuses it for writing). What such an open reads of a
    /// damaged file may be incomplete; its caller says so. (An open that writes refuses a damaged file.)
    const std::string& damage() const { return damage_; }
    /// PRAGMA integrity_check: "ok" or the problems found.
    std::string integrity_check();
    /// ISO 8601 UTC time from the Store's clock, millisecond resolution.
    std::string now_iso8601() const;

    // Sessions ---------------------------------------------------------------------------------------
    std::int64_t create_session(const NewSession& session);
    /// Moves a session to `to`, recording the transition. Throws Kind::invalid for an illegal one.
    void transition(std::int64_t session_id, SessionState to, std::string_view event);
    void start_session(std::int64_t id) { transition(id, SessionState::running, "start"); }
    void finish_session(std::int64_t id) { transition(id, SessionState::completed, "finish"); }
    void abort_session(std::int64_t id, std::string_view why = "abort") { transition(id, SessionState::aborted, why); }
    void fail_session(std::int64_t id, std::string_view why) { transition(id, SessionState::failed, why); }
    /// Resumes an unfinished session (→ `running`): `interrupted`, `failed`, or stored as created/running
    /// with its writer gone (recorded as interrupted first). Returns the seq the next sample gets. Throws
    /// Kind::invalid for a completed or aborted session, or one a live process is writing.
    std::uint64_t resume_session(std::int64_t id);
    /// Records (or replaces) the instrument a session is measured with, e.g. once it has identified.
    void set_instrument(std::int64_t session_id, const Instrument& instrument);
    /// Whether a live process (this Store or another) holds the session's lock: it is being written.
    bool writer_alive(std::int64_t session_id);
    SessionInfo session(std::int64_t id);
    std::vector<SessionInfo> sessions();
    /// A session by numeric id or by a unique prefix of its uuid. Throws Kind::not_found / Kind::invalid.
    std::int64_t find_session(std::string_view id_or_uuid_prefix);
    /// The session's lifecycle (created, running, …, completed), oldest first.
    std::vector<Transition> transitions(std::int64_t session_id);
    /// Records a step of the guided procedure; committed at once (the audit trail of a measurement).
    void add_procedure_step(std::int64_t session_id, const ProcedureStep& step);
    /// The procedure's steps, oldest first. Empty for a schema-v1 file opened read-only: v1 kept them
    /// as results of kind "acquisition.transition" (results() returns those).
    std::vector<ProcedureStep> procedure_steps(std::int64_t session_id);
    /// The file's schema version: kSchemaVersion, or older for a file opened read-only (not migrated).
    int schema_version() const { return schema_version_; }
    void set_notes(std::int64_t session_id, std::string_view notes);

    // Samples (write them with SampleWriter) ----------------------------------------------------------
    std::int64_t sample_count(std::int64_t session_id);
    /// The seq after the last stored sample (0 when none).
    std::uint64_t next_seq(std::int64_t session_id);
    /// Samples with seq in [from_seq, from_seq + limit), in order.
    std::vector<analysis::BarSample> samples(std::int64_t session_id, std::uint64_t from_seq = 0,
                                             std::size_t limit = SIZE_MAX);
    /// Records where a run of samples on one device clock begins (SampleWriter does).
    void add_sample_segment(std::int64_t session_id, const SampleSegment& segment);
    /// The session's segments in seq order; empty for sessions stored before schema v3 (and imported ones).
    std::vector<SampleSegment> sample_segments(std::int64_t session_id);
    /// Records a gap (SampleWriter does, with the batch holding the sample after it).
    void add_sample_gap(std::int64_t session_id, const SampleGap& gap);
    /// The session's gaps in seq order; empty for sessions stored before schema v6.
    std::vector<SampleGap> sample_gaps(std::int64_t session_id);
    /// Sets the instrument's resolution and measured reading rate on the session's segments that start
    /// at `from_seq` or later (the ones a connection or a resume wrote); returns how many it set.
    std::size_t set_segment_instrument(std::int64_t session_id, std::uint64_t from_seq, double resolution_mm,
                                       double reading_rate_hz);
    /// The segment sample `seq` belongs to (the last one starting at or before it), with its instrument
    /// figures: per-sample resolution and rate. Empty when the session records no segment before it.
    std::optional<SampleSegment> segment_of(std::int64_t session_id, std::uint64_t seq);
    /// Calls `fn` for every sample in order, without holding them all in memory.
    void for_each_sample(std::int64_t session_id, const std::function<void(const analysis::BarSample&)>& fn);

    // Points -----------------------------------------------------------------------------------------
    /// Appends a point; returns its index within the session.
    std::int64_t add_point(std::int64_t session_id, const PointRecord& point);
    /// Appends points in order, in one transaction with one prepared statement (an import's batches).
    void add_points(std::int64_t session_id, const std::vector<PointRecord>& points);
    std::vector<PointRecord> points(std::int64_t session_id);

    // Results and models ------------------------------------------------------------------------------
    std::int64_t add_result(std::int64_t session_id, std::string_view kind, std::string_view payload_json,
                            std::optional<std::int64_t> model_id = std::nullopt, std::string_view producer = {});
    std::vector<ResultRecord> results(std::int64_t session_id);
    /// Stores the next version of model `name`.
    ModelRecord save_model(std::string_view name, std::string_view params_json,
                           const std::vector<std::int64_t>& session_ids = {},
                           std::optional<std::int64_t> parent_id = std::nullopt, std::string_view notes = {});
    ModelRecord model(std::int64_t model_id);
    /// All versions of `name`, oldest first.
    std::vector<ModelRecord> model_history(std::string_view name);
    std::optional<ModelRecord> latest_model(std::string_view name);

    // The machine registry and the station (schema v7; docs/fleet.md) ---------------------------------
    /// Registers a machine. Throws Kind::invalid when the asset id is taken (or empty).
    MachineEntry register_machine(const NewMachine& machine);
    /// Registered machines by asset id, then the machines known only by a session's geometry.
    std::vector<MachineEntry> machines();
    /// A registered machine. Throws Kind::not_found naming the asset ids there are.
    MachineEntry machine(std::string_view asset_id);
    /// Changes a registered machine. Throws Kind::invalid for a new geometry of a machine that has
    /// sessions (their analysis rests on the geometry they were measured with: register a new one).
    MachineEntry edit_machine(std::string_view asset_id, const MachineEdit& edit);
    /// This database's own id (made when it was created or migrated to v7).
    std::string station_uuid();

  private:
    void check_file(const std::string& path) const;
    void migrate();
    void recover_unfinished();
    bool try_lock_session(std::int64_t id);
    void unlock_session(std::int64_t id);
    std::int64_t upsert_machine(const analysis::MachineGeometry& machine);
    std::int64_t upsert_instrument(const Instrument& instrument);
    static std::string new_uuid();
    SessionState state_of(std::int64_t session_id);
    ModelRecord read_model(Statement& st);
    void annotate(SessionInfo& s);

    StoreOptions options_;
    Database db_;
    int lock_fd_ = -1;
    int probe_fd_ = -1;                    ///< the lock file opened read-only, for liveness checks of a read-only Store
    int schema_version_ = kSchemaVersion;  // of the file: older only when opened read-only
    std::vector<std::int64_t> owned_;
    std::vector<std::int64_t> recovered_;
    std::string damage_;
};

}  // namespace ballbar::storage
