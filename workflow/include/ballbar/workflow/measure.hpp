// SPDX-License-Identifier: MIT
// The guided two-step SSM measurement as a use case (`ballbar measure`, and the web page to come): a new
// session or one taken up again, the instrument at a device URI (the ball-bar protocol or a digital
// gauge), everything stored as it happens, the session's stored state set as the run ends. The front end
// gives the operator (the questions, the programs to start) and a stop flag, and says what the summary
// means to its user (docs/procedure.md).
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ballbar/acquisition/interfaces.hpp"
#include "ballbar/acquisition/plan.hpp"
#include "ballbar/acquisition/session.hpp"
#include "ballbar/device/transport.hpp"
#include "ballbar/storage/store.hpp"

namespace ballbar::workflow {

/// A session ready to measure: a new one, or one to take up again with the points it has.
struct PreparedSession {
    std::int64_t id = 0;
    acquisition::Plan plan;
    std::vector<acquisition::CapturedPoint> done;  ///< the points a resumed session keeps; empty when new
    std::optional<storage::SessionInfo> before;    ///< a resumed session as it was (its state, why it stopped)
};

/// Creates and starts a session of `plan` (source `emulator` for an `emulator:` URI, else `device`) and
/// stores the plan with it, so that it can be resumed.
/// `machine_asset`: the registry's machine measured (`measure --asset`); empty: known by its geometry.
PreparedSession new_ssm_session(storage::Store& store, const acquisition::Plan& plan, std::string_view device_uri,
                                const std::string& machine_asset = {});

/// Takes up an interrupted session (an id or uuid prefix): its stored plan and points. Error (not found)
/// when no session matches; Error (bad input) when it has no stored plan, or its state forbids going on
/// (completed, aborted, or another process measures it) — nothing is changed then.
PreparedSession resume_ssm_session(storage::Store& store, std::string_view key);

struct SsmMeasureOptions {
    std::string device_uri;
    std::string plan_file;                    ///< named in the message of a bar that does not fit the plan
    const std::atomic<bool>* stop = nullptr;  ///< set: stop, store, stay resumable (Ctrl-C, a page's button)
    /// Opens the link to the ball-bar instead of `device_uri` (which still names the session's device):
    /// an emulator in process on simulated time, for tests and demos. Not for gauges.
    std::function<std::unique_ptr<device::Transport>()> open_transport;
};

/// Runs the procedure on the instrument at `options.device_uri` with `op` answering its questions, from
/// `session.done` on. Stores samples, points, results and the instrument's identity as they come, and
/// sets the session's stored state from how the run ended (completed, interrupted, aborted, failed). The
/// summary says how it ended; what that means to the user is the front end's to say.
acquisition::SessionSummary measure_ssm(storage::Store& store, const PreparedSession& session,
                                        acquisition::Operator& op, const SsmMeasureOptions& options);

}  // namespace ballbar::workflow
