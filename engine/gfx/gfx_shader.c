/* gfx_shader.c — GLSL programs from files in shaders/: #include, errors at file:line, reloading.
 *
 * #include. GLSL has no include, so files are pasted together here. Each file gets a source
 * number and the pasted text carries `#line N SOURCE` directives, so the driver's messages name
 * (source, line); the log is then rewritten to "shaders/FILE:LINE: message". A file is pasted
 * once per program, which also makes include cycles harmless.
 *
 * Reloading. A program remembers every file it was built from and their modification times;
 * gfx_programs_reload_changed rebuilds the programs whose files changed. Handles are indices, so
 * they survive a rebuild; a rebuild that fails keeps the old program and prints the errors. */
#include "gfx_internal.h"

#include "core/core.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define GFX_MAX_SHADER_FILES 32      /* files in one program, includes counted */
#define GFX_MAX_INCLUDE_DEPTH 16
#define GFX_MAX_UNIFORMS 64
#define GFX_MAX_SHADER_BYTES (4u << 20)

typedef struct gfx_uniform_slot { const char *name; GLint location; } gfx_uniform_slot;

struct gfx_program_entry {
    GLuint gl;
    const char *stage_files[3];      /* vertex, fragment, compute (NULL = stage absent) */
    char *names;                     /* storage for stage_files */
    size_t names_size;
    /* Files read for the last build attempt, and when each was modified. */
    char *dependencies[GFX_MAX_SHADER_FILES];
    int64_t modified[GFX_MAX_SHADER_FILES];
    int dependency_count;
    gfx_uniform_slot uniforms[GFX_MAX_UNIFORMS];
    int uniform_count;
};

/* ---- finding the shader folder ---- */

static void gfx_shader_dir_default(char *dir, size_t size) {
    /* Programs live in bin/CONFIG/: the shaders are two folders up. Fall back to ./shaders. */
    char exe[PATH_MAX];
    ssize_t length = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (length > 0) {
        exe[length] = 0;
        char *slash = strrchr(exe, '/');
        if (slash) {
            *slash = 0;
            char candidate[PATH_MAX + 32];
            snprintf(candidate, sizeof candidate, "%s/../../shaders", exe);
            char resolved[PATH_MAX];
            if (realpath(candidate, resolved)) {
                /* Shown relative to the working folder when inside it: shorter messages. */
                char cwd[PATH_MAX];
                size_t cwd_length = getcwd(cwd, sizeof cwd) ? strlen(cwd) : 0;
                if (cwd_length && strncmp(resolved, cwd, cwd_length) == 0 && resolved[cwd_length] == '/')
                    snprintf(dir, size, "%s", resolved + cwd_length + 1);
                else
                    snprintf(dir, size, "%s", resolved);
                return;
            }
        }
    }
    snprintf(dir, size, "shaders");
}

void gfx__programs_init(gfx_context *gfx, const char *shader_dir) {
    /* ENGINE_SHADERS lets a user (or a test) point an installed program at another folder. */
    const char *from_environment = getenv("ENGINE_SHADERS");
    if (!shader_dir && from_environment && *from_environment) shader_dir = from_environment;
    if (shader_dir) snprintf(gfx->shader_dir, sizeof gfx->shader_dir, "%s", shader_dir);
    else gfx_shader_dir_default(gfx->shader_dir, sizeof gfx->shader_dir);
}

static void gfx_entry_forget_files(gfx_program_entry *entry) {
    for (int i = 0; i < entry->dependency_count; i++)
        core_free(entry->dependencies[i], strlen(entry->dependencies[i]) + 1);
    entry->dependency_count = 0;
}

void gfx__programs_destroy(gfx_context *gfx) {
    for (uint32_t i = 0; i < gfx->program_count; i++) {
        gfx_program_entry *entry = &gfx->programs[i];
        if (entry->gl) glDeleteProgram(entry->gl);
        gfx_entry_forget_files(entry);
        if (entry->names) core_free(entry->names, entry->names_size);
    }
    if (gfx->programs) core_free(gfx->programs, gfx->program_capacity * sizeof *gfx->programs);
}

/* ---- reading files with #include ---- */

/* One stage's pasted text. Its files are numbered from 0 (the stage's own file) in the #line
 * directives: drivers that lose track of a directive's source number report 0, which then still
 * names the right file more often than not. */
typedef struct gfx_source {
    char *text;
    size_t length, capacity;
    gfx_program_entry *entry;        /* records every file read, for reloading */
    int files[GFX_MAX_SHADER_FILES]; /* source number → index in entry->dependencies */
    int file_count;
    const char *dir;
    char error[PATH_MAX + 512];
} gfx_source;

static void gfx_source_append(gfx_source *source, const char *text, size_t length) {
    source->text = core_grow(source->text, &source->capacity, source->length + length + 1, 1);
    memcpy(source->text + source->length, text, length);
    source->length += length;
    source->text[source->length] = 0;
}

static void gfx_source_line_directive(gfx_source *source, int line, int file) {
    char directive[48];
    int length = snprintf(directive, sizeof directive, "#line %d %d\n", line, file);
    gfx_source_append(source, directive, (size_t)length);
}

static int64_t gfx_file_modified(const char *path) {
    struct stat info;
    if (stat(path, &info) != 0) return -1;
    return (int64_t)info.st_mtim.tv_sec * 1000000000 + info.st_mtim.tv_nsec;
}

static char *gfx_read_text(const char *path, size_t *size, char *error, size_t error_size) {
    FILE *file = fopen(path, "rb");
    if (!file) {
        snprintf(error, error_size, "cannot read %s: %s", path, strerror(errno));
        return NULL;
    }
    char *text = NULL;
    size_t length = 0, capacity = 0, got;
    char chunk[4096];
    while ((got = fread(chunk, 1, sizeof chunk, file)) > 0) {
        if (length + got > GFX_MAX_SHADER_BYTES) {
            snprintf(error, error_size, "%s is larger than %u bytes", path, GFX_MAX_SHADER_BYTES);
            fclose(file);
            core_free(text, capacity);
            return NULL;
        }
        text = core_grow(text, &capacity, length + got + 1, 1);
        memcpy(text + length, chunk, got);
        length += got;
    }
    fclose(file);
    text = core_grow(text, &capacity, length + 1, 1);
    text[length] = 0;
    *size = capacity;
    return text;
}

/* The quoted name of an `#include "name"` line, or NULL when the line is something else. */
static bool gfx_include_name(const char *line, size_t length, char *name, size_t name_size) {
    size_t i = 0;
    while (i < length && (line[i] == ' ' || line[i] == '\t')) i++;
    if (length - i < 8 || strncmp(line + i, "#include", 8) != 0) return false;
    i += 8;
    while (i < length && (line[i] == ' ' || line[i] == '\t')) i++;
    if (i >= length || line[i] != '"') { name[0] = 0; return true; }
    size_t start = ++i;
    while (i < length && line[i] != '"') i++;
    size_t name_length = i - start;
    if (i >= length || name_length == 0 || name_length >= name_size || memchr(line + start, '/', name_length)) {
        name[0] = 0;   /* malformed: reported by the caller */
        return true;
    }
    memcpy(name, line + start, name_length);
    name[name_length] = 0;
    return true;
}

/* Whether this stage already pasted the file. */
static bool gfx_source_has_file(const gfx_source *source, const char *path) {
    for (int i = 0; i < source->file_count; i++)
        if (strcmp(source->entry->dependencies[source->files[i]], path) == 0) return true;
    return false;
}

static bool gfx_source_add_file(gfx_source *source, const char *name, int depth);

static bool gfx_source_include(gfx_source *source, const char *name, int depth, int line_number,
                               int file_index) {
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s", source->dir, name);
    if (gfx_source_has_file(source, path)) {       /* once per stage */
        gfx_source_line_directive(source, line_number + 1, file_index);
        return true;
    }
    if (!gfx_source_add_file(source, name, depth + 1)) return false;
    gfx_source_line_directive(source, line_number + 1, file_index);
    return true;
}

static bool gfx_source_add_file(gfx_source *source, const char *name, int depth) {
    gfx_program_entry *entry = source->entry;
    if (depth > GFX_MAX_INCLUDE_DEPTH || entry->dependency_count >= GFX_MAX_SHADER_FILES) {
        snprintf(source->error, sizeof source->error, "%s/%s: includes nest deeper than %d or pull in over %d files",
                 source->dir, name, GFX_MAX_INCLUDE_DEPTH, GFX_MAX_SHADER_FILES);
        return false;
    }
    char path[PATH_MAX];
    snprintf(path, sizeof path, "%s/%s", source->dir, name);
    int dependency = entry->dependency_count++;
    entry->dependencies[dependency] = core_strdup(path);
    entry->modified[dependency] = gfx_file_modified(path);
    int file_index = source->file_count++;
    source->files[file_index] = dependency;
    size_t capacity = 0;
    char *text = gfx_read_text(path, &capacity, source->error, sizeof source->error);
    if (!text) return false;
    if (depth > 0) gfx_source_line_directive(source, 1, file_index);
    bool ok = true;
    int line_number = 1;
    for (const char *line = text; *line && ok; line_number++) {
        const char *end = strchr(line, '\n');
        size_t length = end ? (size_t)(end - line) : strlen(line);
        char include[256];
        if (gfx_include_name(line, length, include, sizeof include)) {
            if (!include[0]) {
                snprintf(source->error, sizeof source->error,
                         "%s:%d: #include needs a \"file\" name in the same folder", path, line_number);
                ok = false;
            } else {
                ok = gfx_source_include(source, include, depth, line_number, file_index);
            }
        } else {
            gfx_source_append(source, line, length);
            gfx_source_append(source, "\n", 1);
            /* The root file's #version must stay first; number its lines from here on. */
            if (depth == 0 && line_number == 1) gfx_source_line_directive(source, 2, file_index);
        }
        line = end ? end + 1 : line + length;
    }
    core_free(text, capacity);
    return ok;
}

/* ---- compiling, with messages at file:line ---- */

/* Rewrites a driver message line "0:12(5): error: …" (Mesa), "0(12) : error …" (NVIDIA) or
 * "ERROR: 0:12: …" (AMD) as "FILE:12: error: …". */
static void gfx_report_log_line(const gfx_source *source, const char *line, size_t length) {
    const char *p = line, *end = line + length;
    if (length > 7 && strncmp(p, "ERROR: ", 7) == 0) p += 7;
    else if (length > 9 && strncmp(p, "WARNING: ", 9) == 0) p += 9;
    char *after;
    long file = strtol(p, &after, 10);
    if (after != p && after < end && (*after == ':' || *after == '(')) {
        const char *number = after + 1;
        long line_number = strtol(number, &after, 10);
        if (after != number && file >= 0 && file < source->file_count) {
            while (after < end && (*after == ')' || *after == ':' || *after == ' ' || *after == '('
                                   || (*after >= '0' && *after <= '9'))) after++;
            core_log_error("gfx", "%s:%ld: %.*s", source->entry->dependencies[source->files[file]], line_number,
                       (int)(end - after), after);
            return;
        }
    }
    if (length) core_log_error("gfx", "%.*s", (int)length, line);
}

static void gfx_report_log(const gfx_source *source, const char *log) {
    while (*log) {
        const char *end = strchr(log, '\n');
        size_t length = end ? (size_t)(end - log) : strlen(log);
        gfx_report_log_line(source, log, length);
        log = end ? end + 1 : log + length;
    }
}

static char *gfx_info_log(GLuint object, bool program, size_t *size) {
    GLint length = 0;
    if (program) glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length);
    else glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
    *size = (size_t)(length > 0 ? length : 0) + 1;
    char *log = core_calloc(1, *size);
    if (length > 0) {
        if (program) glGetProgramInfoLog(object, length, NULL, log);
        else glGetShaderInfoLog(object, length, NULL, log);
    }
    return log;
}

static GLuint gfx_compile_stage(const gfx_source *source, GLenum stage, const char *text) {
    GLuint shader = glCreateShader(stage);
    glShaderSource(shader, 1, &text, NULL);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        size_t size;
        char *log = gfx_info_log(shader, false, &size);
        gfx_report_log(source, log);
        core_free(log, size);
        glDeleteShader(shader);
        return 0;
    }
    return shader;
}

static GLuint gfx_link(const GLuint *shaders, int count, const char *name) {
    GLuint program = glCreateProgram();
    for (int i = 0; i < count; i++) glAttachShader(program, shaders[i]);
    glLinkProgram(program);
    for (int i = 0; i < count; i++) glDeleteShader(shaders[i]);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
        size_t size;
        char *log = gfx_info_log(program, true, &size);
        /* Link messages name no source line: print them as they are. */
        core_log_error("gfx", "program %s does not link:\n%s", name, log);
        core_free(log, size);
        glDeleteProgram(program);
        return 0;
    }
    return program;
}

static const GLenum gfx_stage_kinds[3] = { GL_VERTEX_SHADER, GL_FRAGMENT_SHADER, GL_COMPUTE_SHADER };

/* Builds an entry's program from its files; 0 (errors printed) on failure. */
static GLuint gfx_build_from_files(gfx_context *gfx, gfx_program_entry *entry) {
    gfx_entry_forget_files(entry);
    GLuint shaders[3];
    int shader_count = 0;
    bool ok = true;
    for (int stage = 0; stage < 3 && ok; stage++) {
        if (!entry->stage_files[stage]) continue;
        gfx_source source = { .entry = entry, .dir = gfx->shader_dir };
        /* Every stage shares the entry's file list, so source numbers match across stages. */
        ok = gfx_source_add_file(&source, entry->stage_files[stage], 0);
        if (!ok) core_log_error("gfx", "%s", source.error);
        else {
            GLuint shader = gfx_compile_stage(&source, gfx_stage_kinds[stage], source.text);
            if (shader) shaders[shader_count++] = shader;
            else ok = false;
        }
        core_free(source.text, source.capacity);
    }
    if (!ok) {
        for (int i = 0; i < shader_count; i++) glDeleteShader(shaders[i]);
        return 0;
    }
    char name[256];
    snprintf(name, sizeof name, "%s%s%s", entry->stage_files[2] ? entry->stage_files[2] : entry->stage_files[0],
             entry->stage_files[1] ? " + " : "", entry->stage_files[1] ? entry->stage_files[1] : "");
    return gfx_link(shaders, shader_count, name);
}

static gfx_program_entry *gfx_program_entry_new(gfx_context *gfx) {
    gfx->programs = core_grow(gfx->programs, &gfx->program_capacity, gfx->program_count + 1,
                              sizeof *gfx->programs);
    gfx_program_entry *entry = &gfx->programs[gfx->program_count];
    *entry = (gfx_program_entry){ 0 };
    return entry;
}

static gfx_program gfx_program_load_stages(gfx_context *gfx, const char *files[3]) {
    gfx_program_entry *entry = gfx_program_entry_new(gfx);
    /* Keep our own copies of the names: callers may pass temporaries. */
    for (int stage = 0; stage < 3; stage++) entry->names_size += files[stage] ? strlen(files[stage]) + 1 : 0;
    entry->names = core_alloc(entry->names_size);
    char *cursor = entry->names;
    for (int stage = 0; stage < 3; stage++) {
        if (!files[stage]) continue;
        size_t length = strlen(files[stage]) + 1;
        memcpy(cursor, files[stage], length);
        entry->stage_files[stage] = cursor;
        cursor += length;
    }
    entry->gl = gfx_build_from_files(gfx, entry);
    if (!entry->gl) {
        gfx_entry_forget_files(entry);
        core_free(entry->names, entry->names_size);
        return (gfx_program){ 0 };
    }
    return (gfx_program){ ++gfx->program_count };
}

gfx_program gfx_program_load(gfx_context *gfx, const char *vertex_file, const char *fragment_file) {
    return gfx_program_load_stages(gfx, (const char *[3]){ vertex_file, fragment_file, NULL });
}

gfx_program gfx_program_load_compute(gfx_context *gfx, const char *compute_file) {
    return gfx_program_load_stages(gfx, (const char *[3]){ NULL, NULL, compute_file });
}

gfx_program gfx_program_from_source(gfx_context *gfx, const char *name, const char *vertex_source,
                                    const char *fragment_source) {
    gfx_program_entry *entry = gfx_program_entry_new(gfx);
    /* One pseudo-file so messages read "NAME:LINE: …". */
    entry->dependencies[0] = core_strdup(name);
    entry->modified[0] = -1;
    entry->dependency_count = 1;
    gfx_source source = { .entry = entry, .files = { 0 }, .file_count = 1 };
    GLuint shaders[2] = { gfx_compile_stage(&source, GL_VERTEX_SHADER, vertex_source),
                          gfx_compile_stage(&source, GL_FRAGMENT_SHADER, fragment_source) };
    if (!shaders[0] || !shaders[1]) {
        if (shaders[0]) glDeleteShader(shaders[0]);
        if (shaders[1]) glDeleteShader(shaders[1]);
        gfx_entry_forget_files(entry);
        return (gfx_program){ 0 };
    }
    entry->gl = gfx_link(shaders, 2, name);
    if (!entry->gl) { gfx_entry_forget_files(entry); return (gfx_program){ 0 }; }
    return (gfx_program){ ++gfx->program_count };
}

/* ---- reloading ---- */

static bool gfx_entry_changed(const gfx_program_entry *entry) {
    if (!entry->names) return false;     /* built from strings */
    for (int i = 0; i < entry->dependency_count; i++)
        if (gfx_file_modified(entry->dependencies[i]) != entry->modified[i]) return true;
    return false;
}

int gfx_programs_reload_changed(gfx_context *gfx) {
    int rebuilt = 0;
    for (uint32_t i = 0; i < gfx->program_count; i++) {
        gfx_program_entry *entry = &gfx->programs[i];
        if (!gfx_entry_changed(entry)) continue;
        GLuint program = gfx_build_from_files(gfx, entry);   /* records the new times either way */
        if (!program) {
            core_warn("gfx", "kept the previous build of %s", entry->stage_files[0] ? entry->stage_files[0] : entry->stage_files[2]);
            continue;
        }
        glDeleteProgram(entry->gl);
        entry->gl = program;
        entry->uniform_count = 0;
        if (gfx->program_in_use == i + 1) glUseProgram(program);
        core_info("gfx", "reloaded %s%s%s", entry->stage_files[0] ? entry->stage_files[0] : entry->stage_files[2],
                  entry->stage_files[1] ? " + " : "", entry->stage_files[1] ? entry->stage_files[1] : "");
        rebuilt++;
    }
    return rebuilt;
}

/* ---- use and uniforms ---- */

static gfx_program_entry *gfx_entry(const gfx_context *gfx, gfx_program program) {
    if (program.id == 0 || program.id > gfx->program_count) return NULL;
    return &gfx->programs[program.id - 1];
}

GLuint gfx_program_gl(const gfx_context *gfx, gfx_program program) {
    gfx_program_entry *entry = gfx_entry(gfx, program);
    return entry ? entry->gl : 0;
}

void gfx_program_use(gfx_context *gfx, gfx_program program) {
    glUseProgram(gfx_program_gl(gfx, program));
    gfx->program_in_use = program.id;
}

static GLint gfx_uniform_location(gfx_context *gfx, gfx_program program, const char *name) {
    gfx_program_entry *entry = gfx_entry(gfx, program);
    if (!entry) return -1;
    /* Names are usually string literals: compare pointers first. */
    for (int i = 0; i < entry->uniform_count; i++)
        if (entry->uniforms[i].name == name) return entry->uniforms[i].location;
    for (int i = 0; i < entry->uniform_count; i++)
        if (strcmp(entry->uniforms[i].name, name) == 0) return entry->uniforms[i].location;
    GLint location = glGetUniformLocation(entry->gl, name);
    if (entry->uniform_count < GFX_MAX_UNIFORMS)
        entry->uniforms[entry->uniform_count++] = (gfx_uniform_slot){ name, location };
    return location;
}

#define GFX_UNIFORM_SETTER(suffix, type, call)                                                 \
    void gfx_uniform_##suffix(gfx_context *gfx, gfx_program program, const char *name, type value) { \
        GLint location = gfx_uniform_location(gfx, program, name);                             \
        if (location >= 0) call;                                                                \
    }

GFX_UNIFORM_SETTER(float, float, glProgramUniform1f(gfx_program_gl(gfx, program), location, value))
GFX_UNIFORM_SETTER(int, int, glProgramUniform1i(gfx_program_gl(gfx, program), location, value))
GFX_UNIFORM_SETTER(vec2, const float *, glProgramUniform2fv(gfx_program_gl(gfx, program), location, 1, value))
GFX_UNIFORM_SETTER(vec3, const float *, glProgramUniform3fv(gfx_program_gl(gfx, program), location, 1, value))
GFX_UNIFORM_SETTER(vec4, const float *, glProgramUniform4fv(gfx_program_gl(gfx, program), location, 1, value))
GFX_UNIFORM_SETTER(mat4, const float *, glProgramUniformMatrix4fv(gfx_program_gl(gfx, program), location, 1, GL_FALSE, value))
