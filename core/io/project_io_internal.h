// The project file's object writers and readers, shared with the other files that store
// project objects (the recovery file, core/io/recovery_io.h), so that every object is written
// and checked one way. Internal: include it only from core/io .cpp files, so nlohmann stays
// out of the public headers.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/scene/project.h"

namespace facet::project_io_internal {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

// Each object as the project file stores it. `at` is its JSON path: the first value JSON
// cannot hold (NaN, infinity, invalid UTF-8) is named in *error, when *error is still empty.
OrderedJson ObjectToJson(const Image& image, const std::string& at, std::string* error);
OrderedJson ObjectToJson(const Segment& segment, const std::string& at, std::string* error);
OrderedJson ObjectToJson(const Primitive& primitive, const std::string& at, std::string* error);
OrderedJson ObjectToJson(const Pin& pin, const std::string& at, std::string* error);
OrderedJson ObjectToJson(const Constraint& constraint, const std::string& at, std::string* error);
OrderedJson ObjectToJson(const Reference& reference, const std::string& at, std::string* error);
// The whole project file's object ("format": "facet-project", current version).
OrderedJson ProjectToJsonObject(const Project& project, std::string* error);

// Each object read as strictly as the project loader reads it: false with *error naming the
// JSON path under `at`; unknown fields are appended to *warnings. Checks within the object
// only (a mesh's links, a prior's positive focal); references across objects are
// CheckProjectReferences's.
bool ObjectFromJson(const Json& json, const std::string& at, Image* image, std::string* error,
                    std::vector<std::string>* warnings);
bool ObjectFromJson(const Json& json, const std::string& at, Segment* segment, std::string* error,
                    std::vector<std::string>* warnings);
bool ObjectFromJson(const Json& json, const std::string& at, Primitive* primitive, std::string* error,
                    std::vector<std::string>* warnings);
bool ObjectFromJson(const Json& json, const std::string& at, Pin* pin, std::string* error,
                    std::vector<std::string>* warnings);
bool ObjectFromJson(const Json& json, const std::string& at, Constraint* constraint, std::string* error,
                    std::vector<std::string>* warnings);
bool ObjectFromJson(const Json& json, const std::string& at, Reference* reference, std::string* error,
                    std::vector<std::string>* warnings);
// A whole project file's object (older versions migrated, `root` changed in place), with the
// loader's reference checks. Error paths are the project file's (e.g. "pins[2].vertex").
bool ProjectFromJsonObject(Json& root, Project* project, std::string* error, std::vector<std::string>* warnings);
// The loader's checks across objects: ids unique, references resolve, next_id beyond every
// id. Empty when they hold, else the first problem with its path in the project file.
std::string CheckProjectReferences(const Project& project);
// JSON text to a document; false with *error naming the line and column of a syntax error.
bool ParseJson(const std::string& text, Json* root, std::string* error);

}  // namespace facet::project_io_internal
