// SPDX-License-Identifier: MIT
// `ballbar machines add|list|show|edit`: the machine registry (docs/fleet.md). A machine registered
// under the shop's asset id with its machine file; `measure`, `circle measure` and `demo` take it with
// `--asset ID`, and its sessions are listed and trended under it.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "ballbar/storage/store.hpp"
#include "ballbar/workflow/machines.hpp"
#include "command.hpp"

namespace ballbar::app {
namespace {

struct MachinesOptions {
    std::string asset_id;
    std::string machine_file;
    std::optional<std::string> name, location;
    std::optional<double> location_um, angle_arcsec, circularity_um;
    bool json = false;
};

workflow::MachineChange change_of(const MachinesOptions& o) {
    workflow::MachineChange c;
    c.name = o.name;
    c.location = o.location;
    if (!o.machine_file.empty()) {
        c.machine_file_text = read_file(o.machine_file, "machine file");
        c.machine_file_name = o.machine_file;
    }
    c.tolerances.location_um = o.location_um;
    c.tolerances.angle_arcsec = o.angle_arcsec;
    c.tolerances.circularity_um = o.circularity_um;
    return c;
}

std::string or_dash(const std::string& s) {
    return s.empty() ? "-" : s;
}

std::string tolerance_text(const std::optional<double>& v, const char* unit) {
    if (!v) return "-";
    char b[48];
    std::snprintf(b, sizeof b, "%g %s", *v, unit);
    return b;
}

void print_machine(const storage::MachineEntry& m, const acquisition::Tolerances& t, std::ostream& out) {
    out << "machine " << or_dash(m.asset_id) << ": " << m.name << " (" << analysis::to_string(m.type) << ")\n"
        << "  location       " << or_dash(m.location) << '\n'
        << "  registered     " << or_dash(m.registered_at) << (m.updated_at.empty() ? "" : ", edited " + m.updated_at)
        << '\n'
        << "  sessions       " << m.session_count << '\n'
        << "  tolerances     |dV| " << tolerance_text(t.location_um, "µm") << ", angles "
        << tolerance_text(t.angle_arcsec, "\"") << ", G " << tolerance_text(t.circularity_um, "µm") << '\n'
        << "  uuid           " << m.uuid << '\n';
}

int run_machines(const MachinesOptions& o, const Globals& globals, const std::string& verb) {
    if (verb == "add" || verb == "edit") {
        const workflow::MachineChange change = change_of(o);  // the file read (and refused) before a database opens
        if (verb == "add") (void)workflow::machine_file_of(change);
        storage::Store store(verb == "add" ? resolve_db_path(globals) : existing_db_path(globals));
        const auto m = verb == "add" ? workflow::add_machine(store, o.asset_id, change)
                                     : workflow::edit_machine(store, o.asset_id, change);
        if (o.json) {
            std::cout << workflow::machine_json(m) << '\n';
        } else {
            std::cout << (verb == "add" ? "registered " : "changed ") << m.asset_id << '\n';
            print_machine(m, workflow::registered_machine_file(store, m.asset_id).tolerances, std::cout);
        }
        return kExitOk;
    }
    const std::string path = resolve_db_path(globals);
    if (verb == "list" && !std::filesystem::exists(path)) {  // listing creates no database
        std::cout << (o.json ? "[]" : "no machines (no database at " + path + ")") << '\n';
        return kExitOk;
    }
    storage::StoreOptions so;
    so.recover = false;
    storage::Store store(existing_db_path(globals), so);
    note_database_damage(store.damage());
    if (verb == "show") {
        const auto m = store.machine(o.asset_id);
        if (o.json) {
            std::cout << workflow::machine_json(m) << '\n';
        } else {
            print_machine(m, workflow::registered_machine_file(store, o.asset_id).tolerances, std::cout);
        }
        return kExitOk;
    }
    const auto all = store.machines();
    if (o.json) {
        std::cout << workflow::machines_json(all) << '\n';
        return kExitOk;
    }
    if (all.empty()) {
        std::cout << "no machines in " << store.path() << " (ballbar machines add ASSET --machine FILE)\n";
        return kExitOk;
    }
    char line[512];
    std::snprintf(line, sizeof line, "%-14s  %-24s  %-6s  %-20s  %8s\n", "asset", "name", "type", "location",
                  "sessions");
    std::cout << line;
    for (const auto& m : all) {
        std::snprintf(line, sizeof line, "%-14s  %-24s  %-6s  %-20s  %8lld\n",
                      m.asset_id.empty() ? "(unregistered)" : m.asset_id.c_str(), m.name.c_str(),
                      std::string(analysis::to_string(m.type)).c_str(), or_dash(m.location).c_str(),
                      static_cast<long long>(m.session_count));
        std::cout << line;
    }
    return kExitOk;
}

void add_change_options(CLI::App* sub, MachinesOptions& o) {
    sub->add_option("--name", o.name, "the machine's name (default: the machine file's)");
    sub->add_option("--location", o.location, "where it stands: hall, cell");
    sub->add_option("--location-tolerance", o.location_um, "SSM: |ΔV| allowed at each location, µm")
        ->check(in_range(0, 10000, "µm", true));
    sub->add_option("--angle-tolerance", o.angle_arcsec, "SSM: |Δα|, |Δβ|, |Δγ| allowed, arcsec")
        ->check(in_range(0, 36000, "arcsec", true));
    sub->add_option("--circularity-tolerance", o.circularity_um, "circular test: G allowed, µm")
        ->check(in_range(0, 10000, "µm", true));
    sub->add_flag("--json", o.json, "as JSON");
}

}  // namespace
}  // namespace ballbar::app

BALLBAR_COMMAND(machines) {
    auto o = std::make_shared<ballbar::app::MachinesOptions>();
    auto* sub = root.add_subcommand("machines", "The machine registry: machines under their asset ids (docs/fleet.md)");
    sub->require_subcommand(0, 1);  // none: the list
    sub->add_flag("--json", o->json, "as JSON (the list)");
    auto* add = sub->add_subcommand("add", "Register a machine under its asset id, with its machine file");
    add->add_option("ASSET", o->asset_id, "the shop's id for the machine, e.g. M-0042")->required();
    add->add_option("--machine", o->machine_file, "machine file (ballbar-machine/1): geometry, travel, tolerances")
        ->required();
    ballbar::app::add_change_options(add, *o);
    auto* list = sub->add_subcommand("list", "The registered machines, then those known only by a session's geometry");
    list->add_flag("--json", o->json, "as JSON");
    auto* show = sub->add_subcommand("show", "One registered machine");
    show->add_option("ASSET", o->asset_id, "its asset id")->required();
    show->add_flag("--json", o->json, "as JSON");
    auto* edit = sub->add_subcommand("edit", "Change a registered machine (its geometry only while it has no session)");
    edit->add_option("ASSET", o->asset_id, "its asset id")->required();
    edit->add_option("--machine", o->machine_file, "a new machine file");
    ballbar::app::add_change_options(edit, *o);
    sub->callback([o, add, show, edit, &globals] {
        const std::string verb = add->parsed() ? "add" : show->parsed() ? "show" : edit->parsed() ? "edit" : "list";
        globals.action = [o, verb, &globals] { return ballbar::app::run_machines(*o, globals, verb); };
    });
}
