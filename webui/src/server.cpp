// SPDX-License-Identifier: MIT
#include "ballbar/webui/server.hpp"

#include <arpa/inet.h>
#include <sys/socket.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "assets.hpp"
#include "ballbar/report/build.hpp"
#include "ballbar/report/report.hpp"
#include "ballbar/storage/session_export.hpp"
#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/error.hpp"
#include "ballbar/workflow/import_export.hpp"
#include "ballbar/workflow/trend.hpp"
// Last: httplib.h brings <resolv.h>, whose `_res` macro breaks Eigen's headers included after it.
#include <httplib.h>

namespace ballbar::webui {

using json = nlohmann::json;
using workflow::ErrorCategory;

bool is_loopback(const std::string& host) {
    if (host == "localhost" || host == "::1") return true;
    in_addr a{};
    return ::inet_pton(AF_INET, host.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

std::string random_token() {
    std::ifstream in("/dev/urandom", std::ios::binary);
    unsigned char b[16];
    if (!in.read(reinterpret_cast<char*>(b), sizeof b))
        throw workflow::Error(ErrorCategory::failed, "cannot read /dev/urandom for a token");
    std::string hex;
    char d[3];
    for (unsigned char c : b) {
        std::snprintf(d, sizeof d, "%02x", c);
        hex += d;
    }
    return hex;
}

namespace {

constexpr auto kTick = std::chrono::milliseconds(20);  // the live stream's 50 Hz

int status_of(ErrorCategory c) {
    switch (c) {
        case ErrorCategory::bad_input:
            return 400;
        case ErrorCategory::not_found:
            return 404;
        case ErrorCategory::interrupted:
            return 409;
        case ErrorCategory::device:
        case ErrorCategory::failed:
            return 422;
        case ErrorCategory::internal:
            return 500;
    }
    return 500;
}

void send_error(httplib::Response& res, int status, const std::string& message) {
    res.status = status;
    res.set_content(json{{"error", message}}.dump(), "application/json");
}

/// A query parameter that must be a number > 0 when given (a tolerance); ApiError 400 naming it otherwise.
std::optional<double> positive_param(const httplib::Request& req, const char* name) {
    if (!req.has_param(name) || req.get_param_value(name).empty()) return std::nullopt;
    const std::string text = req.get_param_value(name);
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end != text.c_str() + text.size() || !(v > 0) || !std::isfinite(v))
        throw ApiError(400, std::string(name) + " must be a number > 0, not \"" + text + "\"");
    return v;
}

/// Equal in a time that does not tell how much of the token was right.
bool same_token(const std::string& a, const std::string& b) {
    if (a.size() != b.size() || b.empty()) return false;
    unsigned char diff = 0;
    for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
    return diff == 0;
}

}  // namespace

struct Server::Impl {
    ServeOptions o;
    httplib::Server http;
    Procedure procedure;
    std::atomic<bool> stopping{false};
    std::atomic<bool> serving{false};  // run() has been entered and has not returned
    std::once_flag stopped;

    explicit Impl(ServeOptions options) : o(std::move(options)), procedure(o.db_path) {}

    // ---- who may ask -------------------------------------------------------------------------------

    bool authorized(const httplib::Request& req) const {
        if (o.token.empty()) return true;
        const std::string auth = req.get_header_value("Authorization");
        if (auth.rfind("Bearer ", 0) == 0 && same_token(auth.substr(7), o.token)) return true;
        return req.has_param("token") && same_token(req.get_param_value("token"), o.token);
    }

    /// The Host the browser asked for names this server (not a rebound DNS name): on a loopback address
    /// without a token, only a loopback name is taken.
    bool host_ok(const httplib::Request& req) const {
        if (!o.token.empty() || !is_loopback(o.host)) return true;
        std::string host = req.get_header_value("Host");
        if (host.empty()) return true;  // HTTP/1.0 clients (curl -0): no name to rebind
        if (host.front() == '[')
            host = host.substr(1, host.find(']') - 1);
        else
            host = host.substr(0, host.find(':'));
        return is_loopback(host);
    }

    /// A write comes from this server's own page (or a script): never from another site's page.
    std::string write_refusal(const httplib::Request& req) const {
        const std::string origin = req.get_header_value("Origin");
        if (!origin.empty() && origin != "http://" + req.get_header_value("Host"))
            return "cross-origin request refused (Origin " + origin + ")";
        if (req.get_header_value("Content-Type").rfind("application/json", 0) != 0)
            return "a write must be Content-Type: application/json";
        return {};
    }

    static std::string client_of(const httplib::Request& req) {
        std::string c = req.get_header_value("X-Ballbar-Client");
        if (c.empty() && req.has_param("client")) c = req.get_param_value("client");
        if (c.size() > 64) c.resize(64);
        return c;
    }

    // ---- sessions ----------------------------------------------------------------------------------

    std::unique_ptr<storage::Store> reader() const {
        if (!std::filesystem::exists(o.db_path)) return nullptr;
        storage::StoreOptions so;
        so.read_only = true;
        so.recover = false;  // a reader must not touch a running procedure's session
        return std::make_unique<storage::Store>(o.db_path, so);
    }

    template <typename F>
    void with_session(const httplib::Request& req, httplib::Response& res, F&& f) const {
        auto store = reader();
        const std::string key = req.matches[1];
        if (!store) return send_error(res, 404, "no session \"" + key + "\" (no database yet)");
        f(*store, store->find_session(key));
    }

    // ---- routes ------------------------------------------------------------------------------------

    void routes() {
        http.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
            res.set_header("X-Content-Type-Options", "nosniff");
            res.set_header("Cache-Control", "no-store");
            if (!host_ok(req)) {
                send_error(res, 403, "unknown Host: use http://127.0.0.1:" + std::to_string(req.local_port) + "/");
                return httplib::Server::HandlerResponse::Handled;
            }
            if (!authorized(req)) {
                send_error(res, 401, "a token is needed: open the address `ballbar serve` printed (…/?token=…)");
                return httplib::Server::HandlerResponse::Handled;
            }
            if (req.method != "GET" && req.method != "HEAD") {
                if (const auto why = write_refusal(req); !why.empty()) {
                    send_error(res, 403, why);
                    return httplib::Server::HandlerResponse::Handled;
                }
            }
            return httplib::Server::HandlerResponse::Unhandled;
        });
        http.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
            try {
                std::rethrow_exception(ep);
            } catch (const ApiError& e) {
                send_error(res, e.status(), e.what());
            } catch (const json::exception& e) {
                send_error(res, 400, std::string("malformed request: ") + e.what());
            } catch (const std::exception& e) {
                send_error(res, status_of(workflow::category_of(e)), e.what());
            } catch (...) {
                send_error(res, 500, "unknown error");
            }
        });
        for (const Asset& a : assets()) {
            const std::string path = a.path == "/index.html" ? "/" : std::string(a.path);
            http.Get(path, [&a](const httplib::Request&, httplib::Response& res) {
                res.set_content(a.body.data(), a.body.size(), std::string(a.content_type).c_str());
            });
        }
        http.Get("/api/procedure", [this](const httplib::Request& req, httplib::Response& res) {
            res.set_content(procedure.snapshot(client_of(req)).dump(), "application/json");
        });
        http.Post("/api/procedure", [this](const httplib::Request& req, httplib::Response& res) {
            res.set_content(procedure.start(json::parse(req.body), client_of(req)).dump(), "application/json");
        });
        http.Post("/api/procedure/answer", [this](const httplib::Request& req, httplib::Response& res) {
            const json a = json::parse(req.body);
            procedure.answer(a.at("question").get<std::uint64_t>(), a.at("option").get<std::size_t>(), client_of(req));
            res.set_content(R"({"answered":true})", "application/json");
        });
        http.Post("/api/procedure/stop", [this](const httplib::Request& req, httplib::Response& res) {
            procedure.stop(client_of(req));
            res.set_content(R"({"stopping":true})", "application/json");
        });
        http.Get("/api/procedure/program", [this](const httplib::Request&, httplib::Response& res) {
            const json s = procedure.snapshot();
            if (!s.value("program", json()).is_object()) return send_error(res, 404, "no program to run now");
            res.set_header("Content-Disposition", "attachment; filename=\"ballbar-ssm.nc\"");
            res.set_content(s["program"]["text"].get<std::string>(), "text/plain; charset=utf-8");
        });
        http.Get("/api/events", [this](const httplib::Request& req, httplib::Response& res) { events(req, res); });
        http.Get("/api/sessions", [this](const httplib::Request&, httplib::Response& res) {
            auto store = reader();
            res.set_content(store ? storage::sessions_json(*store) : "[]", "application/json");
        });
        http.Get("/api/trend", [this](const httplib::Request& req, httplib::Response& res) {
            if (!req.has_param("machine")) throw ApiError(400, "give ?machine=LABEL (as the session list shows it)");
            const std::string machine = req.get_param_value("machine");
            auto store = reader();
            res.set_content(workflow::trend_json(machine, store ? workflow::machine_trend(*store, machine)
                                                                : std::vector<workflow::TrendPoint>{}),
                            "application/json");
        });
        http.Get(R"(/api/sessions/([0-9A-Za-z-]+))", [this](const httplib::Request& req, httplib::Response& res) {
            with_session(req, res, [&](storage::Store& s, std::int64_t id) {
                res.set_content(storage::session_json(s, id, true), "application/json");
            });
        });
        http.Get(R"(/api/sessions/([0-9A-Za-z-]+)/report\.(json|pdf))",
                 [this](const httplib::Request& req, httplib::Response& res) {
                     with_session(req, res, [&](storage::Store& s, std::int64_t id) {
                         report::BuildOptions bo;
                         bo.software_version = o.software_version;
                         report::Report r = report::build_report(s, id, bo);
                         if (const auto t = positive_param(req, "tolerance_um")) report::set_circular_tolerance(r, *t);
                         report::set_ssm_tolerances(r, positive_param(req, "location_tolerance_um"),
                                                    positive_param(req, "angle_tolerance_arcsec"));
                         if (req.matches[2] == "json") {
                             res.set_content(report::to_json(r).dump(), "application/json");
                             return;
                         }
                         res.set_header("Content-Disposition",
                                        "attachment; filename=\"ballbar-session-" + std::to_string(id) + ".pdf\"");
                         res.set_content(report::render_pdf_bytes(r), "application/pdf");
                     });
                 });
        http.Get(
            R"(/api/sessions/([0-9A-Za-z-]+)/export)", [this](const httplib::Request& req, httplib::Response& res) {
                with_session(req, res, [&](storage::Store& s, std::int64_t id) {
                    const std::string f = req.has_param("format") ? req.get_param_value("format") : "json";
                    const auto format = f == "readings" ? workflow::ExportFormat::readings
                                        : f == "trace"  ? workflow::ExportFormat::trace
                                        : f == "json"   ? workflow::ExportFormat::json
                                                        : throw ApiError(400, "format must be json, readings or trace");
                    const std::string ext = f == "json" ? "json" : f == "trace" ? "trace.csv" : "readings.csv";
                    res.set_header("Content-Disposition",
                                   "attachment; filename=\"ballbar-session-" + std::to_string(id) + "." + ext + "\"");
                    res.set_content(workflow::export_session(s, id, format),
                                    f == "json" ? "application/json" : "text/plain; charset=utf-8");
                });
            });
        http.set_error_handler([](const httplib::Request&, httplib::Response& res) {
            if (res.body.empty()) send_error(res, res.status, "no such page or API (docs/webui.md)");
        });
    }

    /// Server-Sent Events: "state" whenever the procedure's state changes, "live" with the bar reading at
    /// up to 50 Hz while it changes, a comment every second so a closed page is noticed (its steering
    /// passes to the next screen within about two seconds).
    void events(const httplib::Request& req, httplib::Response& res) {
        if (procedure.viewers() >= static_cast<std::size_t>(o.max_viewers))
            return send_error(res, 503, "too many screens watch already (" + std::to_string(o.max_viewers) + ")");
        const std::string client = client_of(req);
        procedure.viewer(client, true);
        struct Cursor {
            std::uint64_t version = 0, live = 0;
            std::chrono::steady_clock::time_point last_live{}, last_sent = std::chrono::steady_clock::now();
        };
        auto cur = std::make_shared<Cursor>();
        res.set_header("X-Accel-Buffering", "no");
        res.set_chunked_content_provider(
            "text/event-stream",
            [this, cur, client](std::size_t, httplib::DataSink& sink) {
                if (stopping) return false;
                procedure.wait_change(cur->version, kTick);  // a state at once; the reading on the tick
                if (stopping) return false;
                std::string out;
                const auto now = std::chrono::steady_clock::now();
                if (const auto v = procedure.version(); v != cur->version) {
                    json s = procedure.snapshot(client);
                    cur->version = s["version"].get<std::uint64_t>();
                    out += "event: state\ndata: " + s.dump() + "\n\n";
                }
                const LiveReading l = procedure.live();
                if (l.seq != cur->live && now - cur->last_live >= kTick - std::chrono::milliseconds(2)) {
                    cur->live = l.seq;
                    cur->last_live = now;
                    char buf[200];
                    std::snprintf(buf, sizeof buf,
                                  "event: live\ndata: {\"seq\":%llu,\"bar_mm\":%.6f,\"expected_mm\":%.6f,"
                                  "\"range_mm\":%.3f,\"out_of_range\":%s,\"fill\":%.3f}\n\n",
                                  static_cast<unsigned long long>(l.seq), l.bar_mm, l.expected_mm, l.range_mm,
                                  l.out_of_range ? "true" : "false", l.fill);
                    out += buf;
                }
                if (out.empty() && now - cur->last_sent > std::chrono::seconds(1)) out = ": still here\n\n";
                if (out.empty()) return true;
                cur->last_sent = now;
                return sink.write(out.data(), out.size());
            },
            [this, client](bool) { procedure.viewer(client, false); });
    }
};

Server::Server(ServeOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {
    auto& http = impl_->http;
    // cpp-httplib's default socket options add SO_REUSEPORT: a second server would share the port and
    // requests would alternate between them. SO_REUSEADDR only: the second one fails to bind.
    http.set_socket_options([](socket_t s) {
        int yes = 1;
        ::setsockopt(s, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    });
    http.set_keep_alive_timeout(1);  // an idle browser connection must not hold up a stop for 5 s
    // Each event stream holds a worker: room for every viewer and the requests beside them.
    const int workers = impl_->o.max_viewers + 16;
    http.new_task_queue = [workers] { return new httplib::ThreadPool(static_cast<std::size_t>(workers)); };
    impl_->routes();
}

Server::~Server() {
    stop();
}

int Server::bind() {
    const auto& o = impl_->o;
    const int port =
        o.port == 0 ? impl_->http.bind_to_any_port(o.host) : (impl_->http.bind_to_port(o.host, o.port) ? o.port : -1);
    if (port < 0)
        throw workflow::Error(ErrorCategory::bad_input,
                              "cannot listen on " + o.host + ":" + std::to_string(o.port) +
                                  " (the port is in use, or the address is not this machine's): give --port");
    return port;
}

void Server::run() {
    impl_->serving = true;
    if (!impl_->stopping) impl_->http.listen_after_bind();
    impl_->serving = false;
}

void Server::stop() {
    std::call_once(impl_->stopped, [this] {
        impl_->stopping = true;
        impl_->procedure.shutdown();  // the session ends interrupted, everything measured stored
        // cpp-httplib's stop() does nothing before its listen loop runs: a stop that comes between run()'s
        // start and the loop's is repeated until run() has returned (run() itself checks `stopping` first).
        impl_->http.stop();
        while (impl_->serving) {
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            impl_->http.stop();
        }
    });
}

Procedure& Server::procedure() {
    return impl_->procedure;
}

}  // namespace ballbar::webui
