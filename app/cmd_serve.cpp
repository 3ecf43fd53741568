// SPDX-License-Identifier: MIT
// `ballbar serve [--host H] [--port P] [--token-file F] [--demo]`: the guided procedures, the sessions and
// their reports as a local web page (webui/, docs/webui.md). Runs until SIGINT/SIGTERM; a procedure
// running then stops keeping everything it measured (resumable), and the command exits 0.
#include <pthread.h>
#include <signal.h>

#include <cstdio>
#include <iostream>
#include <memory>
#include <thread>

#include "ballbar/version.hpp"
#include "ballbar/webui/server.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

struct ServeCliOptions {
    std::string host = "127.0.0.1";
    int port = 8230;
    std::string token_file;
    bool demo = false;
};

std::string read_token(const std::string& path) {
    std::string t = read_file(path, "token file");
    while (!t.empty() && (t.back() == '\n' || t.back() == '\r' || t.back() == ' ')) t.pop_back();
    if (t.size() < 16) throw Error(ErrorCategory::bad_input, path + ": a token of at least 16 characters is needed");
    for (char c : t)
        if (c <= ' ' || c > '~') throw Error(ErrorCategory::bad_input, path + ": the token must be printable ASCII");
    return t;
}

int run_serve(const ServeCliOptions& o, const Globals& globals) {
    webui::ServeOptions so;
    so.host = o.host;
    so.port = o.port;
    so.db_path = resolve_db_path(globals);
    so.software_version = kVersion;
    if (!o.token_file.empty())
        so.token = read_token(o.token_file);
    else if (!webui::is_loopback(o.host))
        so.token = webui::random_token();  // other machines reach it: a token

    // SIGINT and SIGTERM go to one thread that stops the server; every other thread (the server's pool,
    // the procedure's) inherits the mask set here, before any of them starts.
    sigset_t signals;
    sigemptyset(&signals);
    sigaddset(&signals, SIGINT);
    sigaddset(&signals, SIGTERM);
    sigset_t before;
    pthread_sigmask(SIG_BLOCK, &signals, &before);
    struct Restore {
        sigset_t mask;
        ~Restore() { pthread_sigmask(SIG_SETMASK, &mask, nullptr); }
    } restore{before};

    webui::Server server(so);
    const int port = server.bind();
    std::string url = "http://" + (o.host.find(':') != std::string::npos ? "[" + o.host + "]" : o.host) + ":" +
                      std::to_string(port) + "/";
    if (!so.token.empty()) url += "?token=" + so.token;
    std::cout << "ballbar serve: open " << url << "\n"
              << "  sessions in " << so.db_path << "; Ctrl-C stops (a running procedure keeps what it measured)"
              << std::endl;
    if (o.demo) {  // the circular demo, waiting at its first question for the first screen that opens
        server.procedure().start({{"procedure", "circular"}, {"demo", true}}, "ballbar serve --demo");
    }
    std::thread waiter([&server, signals] {
        int sig = 0;
        sigwait(&signals, &sig);
        if (sig != 0) server.stop();
    });
    server.run();
    server.stop();  // run() ended on its own (it should not): stop the rest as a signal would
    pthread_kill(waiter.native_handle(), SIGTERM);  // wakes the waiter if no signal came
    waiter.join();
    std::cerr << "ballbar serve: stopped" << std::endl;
    return kExitOk;
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(serve) {
    using namespace ballbar::app;
    auto o = std::make_shared<ServeCliOptions>();
    auto* sub = root.add_subcommand("serve", "Serve the guided procedures and the sessions as a local web page");
    sub->add_option("--host", o->host, "Address to listen on (default 127.0.0.1; any other needs a token)");
    sub->add_option("--port", o->port, "TCP port (0: any free one)")->check(CLI::Range(0, 65535));
    sub->add_option("--token-file", o->token_file,
                    "File holding the token every request must carry (default: none on 127.0.0.1, a random one "
                    "printed otherwise)");
    sub->add_flag("--demo", o->demo, "Start the circular demo on the emulator for the first screen that opens");
    sub->callback([o, &globals] { globals.action = [o, &globals] { return run_serve(*o, globals); }; });
}
