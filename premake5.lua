-- premake5.lua — the build. Runs under premake5 and under Debian's premake4:
--     premake4 --file=premake5.lua --to=build gmake && make -C build config=release
-- (tools/build does this for you and is what play, test and bench call).
--
-- Configurations
--   debug    -O1 -g, AddressSanitizer + UndefinedBehaviorSanitizer (-O1, as the sanitizers
--            advise: the tests run twice as fast as at -O0, and every check is kept)
--   release  -O2 -g, portable x86-64 (no CPU-specific flags: runs on any x86-64)
--   tsan     -O1 -g, ThreadSanitizer (job-system and scheduler tests)
--
-- Adding code: a .c file under engine/ joins the engine library, a test file under
-- tests/engine/ joins the test runner; nothing here needs to change. A new program is a
-- `program { ... }` call at the bottom.

local premake5 = _PREMAKE_VERSION ~= nil and string.sub(_PREMAKE_VERSION, 1, 1) ~= "4"

-- premake4 scopes settings with configuration(), premake5 with filter().
local function only(cfg)
  if premake5 then filter("configurations:" .. cfg) else configuration(cfg) end
end
local function all_configs()
  if premake5 then filter({}) else configuration({}) end
end

-- The OpenGL loader is generated, not written: Debian's glad 2 writes it into build/glad the
-- first time the makefiles are generated (--reproducible keeps it offline and byte-stable).
local glad_dir = "build/glad"
if not os.isfile(glad_dir .. "/src/gl.c") then
  os.execute("glad --reproducible --api gl:core=4.5 --out-path " .. glad_dir .. " c >/dev/null 2>&1")
  if not os.isfile(glad_dir .. "/src/gl.c") then
    error("could not generate the OpenGL loader with glad (install python3-glad: tools/setup)")
  end
end

if premake5 then workspace "engine" else solution "engine" end
  configurations { "debug", "release", "tsan" }
  location(_OPTIONS["to"] or "build")
  objdir "build/obj"
  language "C"
  includedirs { "engine", "modules", ".", glad_dir .. "/include" }   -- "." for game/*.h
  defines { "_GNU_SOURCE" }
  buildoptions { "-std=c11", "-Wall", "-Wextra", "-Wshadow", "-Wno-missing-field-initializers",
                 "-pthread" }
  linkoptions { "-pthread" }
  -- Keep the symbols in the programs: premake4 links with -s unless told, and a stripped
  -- program leaves sanitizer reports, perf and gdb with bare addresses.
  if premake5 then symbols "On" else flags { "Symbols" } end

  only "debug"
    targetdir "bin/debug"
    defines { "ENGINE_DEBUG" }
    buildoptions { "-O1", "-fsanitize=address,undefined", "-fno-omit-frame-pointer",
                   "-fno-sanitize-recover=undefined" }
    linkoptions { "-fsanitize=address,undefined" }
  only "release"
    targetdir "bin/release"
    defines { "NDEBUG" }
    buildoptions { "-O2" }
  only "tsan"
    targetdir "bin/tsan"
    defines { "ENGINE_TSAN" }
    buildoptions { "-O1", "-fsanitize=thread", "-fno-omit-frame-pointer" }
    linkoptions { "-fsanitize=thread" }
  all_configs()

project "engine"
  kind "StaticLib"
  files { "engine/**.c", "engine/**.h" }

-- The game: the walkable world built on the modules (game/**.c).
project "game"
  kind "StaticLib"
  files { "game/**.c", "game/**.h" }
  excludes { "game/main.c" }

-- Modules: one library each, built on the engine (modules/NAME/**.c: area folders too, such as
-- modules/terrain/data/; object names stay unique because every file carries its module prefix).
project "terrain"
  kind "StaticLib"
  files { "modules/terrain/**.c", "modules/terrain/**.h" }

project "vegetation"
  kind "StaticLib"
  files { "modules/vegetation/**.c", "modules/vegetation/**.h" }

project "rocks"
  kind "StaticLib"
  files { "modules/rocks/**.c", "modules/rocks/**.h" }

-- Generated code: built with its own warnings off, so ours can stay strict.
project "glad"
  kind "StaticLib"
  files { glad_dir .. "/src/gl.c" }
  buildoptions { "-w" }

-- What the engine's platform layer (engine/gfx, engine/input) and the world database
-- (modules/terrain/data/terrain_store.c) link against.
local platform_libs = { "glfw", "OSMesa", "hidapi-hidraw", "stb", "meshoptimizer", "sqlite3", "dl" }

-- A program linked against the engine. `extra` may set files, links and build options.
local function program(name, extra)
  project(name)
    kind "ConsoleApp"
    files(extra.files)
    if extra.excludes then excludes(extra.excludes) end
    if extra.defines then defines(extra.defines) end
    links { "game", "vegetation", "rocks", "terrain", "engine", "glad" }
    if extra.links then links(extra.links) end
    links(platform_libs)
    links { "m" }
    if extra.buildoptions then buildoptions(extra.buildoptions) end
    if extra.linkoptions then linkoptions(extra.linkoptions) end
end

program("test_engine", { files = { "tests/engine/**.c", "tests/engine/**.h" },
                         excludes = { "tests/engine/test_shim.c" },
                         links = { "criterion" } })
-- The tests that exercise threads, without Criterion, so they can run under ThreadSanitizer
-- (tests/engine/test.h says why). tools/test builds and runs this in the tsan configuration.
program("test_threads", { files = { "tests/engine/test_shim.c", "tests/engine/test_jobs.c",
                                    "tests/engine/test_jobs_trace.c",
                                    "tests/engine/test_ecs_scheduler.c", "tests/engine/test_ecs_commands.c",
                                    "tests/engine/test_ecs_hooks.c", "tests/engine/test_ecs_observers.c",
                                    "tests/engine/test_ecs_resources.c",
                                    "tests/engine/test_trace.c", "tests/engine/test_input_threads.c",
                                    "tests/terrain/test_terrain_threads.c", "tests/terrain/test_terrain_ecs_edit.c",
                                    "tests/rocks/test_rocks_threads.c" },
                          defines = { "TEST_WITHOUT_CRITERION" } })
program("bench", { files = { "tools/src/bench/**.c", "tools/src/bench/**.h" },
                   buildoptions = { "-fopenmp" }, linkoptions = { "-fopenmp" } })
program("trace_report", { files = { "tools/src/trace_report.c" } })
program("hidreplay", { files = { "tools/src/hidreplay.c" } })
program("test_terrain", { files = { "tests/terrain/**.c", "tests/terrain/**.h" }, links = { "criterion" } })
program("terrain_export", { files = { "tools/src/terrain_export.c" } })
program("terrain_mesh", { files = { "tools/src/terrain_mesh.c" } })
program("test_rocks", { files = { "tests/rocks/**.c", "tests/rocks/**.h" }, links = { "criterion" } })
program("rocks_export", { files = { "tools/src/rocks_export.c" } })
-- Render tests: OSMesa scenes checked by image properties and a golden PNG; a window test when
-- there is a display (tools/test starts Xvfb for it).
program("test_render", { files = { "tests/render/**.c", "tests/render/**.h" }, links = { "criterion" } })
program("world", { files = { "game/main.c" } })
-- Examples: every tools/examples/AREA/MODULE_FEATURE.c is a program of that name, built with
-- warnings as errors (tools/examples/README.md). TEMPLATE.c builds too, so it stays correct.
local examples = os.matchfiles("tools/examples/**.c")
table.sort(examples)
for _, path in ipairs(examples) do
  program(path:match("([^/]+)%.c$"), { files = { path }, buildoptions = { "-Werror" } })
end
program("test_game", { files = { "tests/game/**.c", "tests/game/**.h" }, links = { "criterion" } })
