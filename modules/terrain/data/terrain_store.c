/* terrain_store.c — the world folder as one SQLite database (terrain.h, "the world folder").
 *
 * DIR/world.db, application_id 0x54455752 ("TEWR"), user_version = STORE_FORMAT (1):
 *
 *   settings(name TEXT PRIMARY KEY, value TEXT NOT NULL)
 *       seed           the world seed, decimal
 *       world_key      terrain_generation_key, 16 hex digits: what a load checks
 *       format         STORE_FORMAT again, for people reading the file with sqlite3
 *       imported_edits present once an old DIR/edits folder was imported (how many chunks)
 *   chunks(x INTEGER, z INTEGER, edits BLOB NOT NULL, PRIMARY KEY (x, z)) WITHOUT ROWID
 *       one row per edited chunk: `edits` is the chunk's edit file, byte for byte (the format
 *       at the top of terrain_edit_log.c: magic, version, world key, coordinate, entries,
 *       CRC-32), so replay and compaction keep their code and each blob checks itself
 *   data(name TEXT PRIMARY KEY, value BLOB NOT NULL) WITHOUT ROWID
 *       named values other code saves with the world (terrain_store_put)
 *
 * Why these choices:
 *   - One transaction per save: the reason the store exists. Files renamed one by one cannot
 *     make an edit that spans chunks atomic; SQLite's commit can, and is tested for it far
 *     beyond what a hand-made store could be.
 *   - WAL mode: a commit appends pages to world.db-wal and fsyncs that one file (synchronous =
 *     FULL); a rollback journal would fsync twice and rewrite pages in place.
 *   - locking_mode = EXCLUSIVE: the store takes SQLite's exclusive lock when it opens and keeps
 *     it until it closes, so a second process is refused at once (SQLITE_BUSY, busy timeout 0)
 *     instead of both writing. It also means no -shm file: the WAL index lives in our memory.
 *   - Blobs are whole edit files: a flipped bit in a chunk is caught by its CRC even where
 *     SQLite's own checks (quick_check) see a well-formed page.
 *
 * Threads: `db_lock` guards the connection (one transaction at a time: a save, or the store's
 * opening). `order` makes snapshots commit in the order they were taken (a save waits for the
 * one in flight before taking its own). `lock` guards the named values and the hand-over to the
 * save thread. The save thread starts on the first terrain_store_save_async and sleeps on
 * `wake` otherwise.
 */
#include "terrain/data/terrain_data_internal.h"

#include "core/core.h"
#include "trace/trace.h"

#include <errno.h>
#include <inttypes.h>
#include <pthread.h>
#include <sqlite3.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define STORE_FILE "world.db"
#define STORE_APPLICATION_ID 0x54455752   /* "TEWR": terrain world */
#define STORE_FORMAT 1
#define STORE_NAME_MAX 63
#define STORE_VALUE_MAX ((size_t)1 << 20)
#define VALUE_ALLOC(size) ((size) ? (size) : 1)   /* an empty value still owns a byte */
/* Every chunk with more than one entry is compacted before it is saved (terrain_edit_log_compact:
 * one entry with each edited column's final layers). The world folder then holds one entry per
 * edited chunk, its size bounded by the columns edited, not by the frames played: a slide that
 * stabilizes over 10 000 frames appends 10 000 entries to the log, and the next save folds them.
 * The fold is in memory too, so the log's memory is bounded at every save. It also keeps each
 * blob under SQLite's default limit of 10^9 bytes (a compacted chunk takes at most about
 * 336 MB). */
#define STORE_COMPACT_ABOVE 0

/* ---- named values ------------------------------------------------------------------------ */

typedef struct store_value {
    char name[STORE_NAME_MAX + 1];
    uint8_t *bytes;
    size_t size;
    uint64_t version, saved_version;  /* dirty while they differ */
} store_value;

typedef struct store_value_copy {
    char name[STORE_NAME_MAX + 1];
    uint8_t *bytes;
    size_t size;
    uint64_t version;
} store_value_copy;

/* What one save writes: taken on the caller's thread, written on any. */
typedef struct store_snapshot {
    terrain__edit_files chunks;
    store_value_copy *values;
    size_t value_count, value_capacity;
    char imported_edits[32];          /* the import's marker, committed with its chunks; or "" */
} store_snapshot;

struct terrain_store {
    char *dir, *path;
    terrain_edit_log *edits;
    sqlite3 *db;
    sqlite3_stmt *put_chunk, *put_value;
    pthread_mutex_t db_lock;
    pthread_mutex_t order;            /* snapshots are committed in the order they are taken */
    pthread_mutex_t lock;
    pthread_cond_t wake, done;
    pthread_t thread;
    bool thread_started, stopping;
    store_snapshot *queued;           /* handed to the thread, NULL when none */
    bool busy;                        /* a snapshot queued or being written */
    bool last_ok;
    core_error last_error;            /* of the last save, for terrain_store_wait */
    store_value *values;
    size_t value_count, value_capacity;
};

/* ---- small helpers ----------------------------------------------------------------------- */

static bool path_exists(const char *path) {
    struct stat info;
    return stat(path, &info) == 0;
}

static bool is_folder(const char *path) {
    struct stat info;
    return stat(path, &info) == 0 && S_ISDIR(info.st_mode);
}

/* Runs SQL that returns no rows; the SQLite result code. */
static int exec(sqlite3 *db, const char *sql) {
    return sqlite3_exec(db, sql, NULL, NULL, NULL);
}

/* The first column of the first row as an integer (0 when no row); the SQLite result code. */
static int query_int(sqlite3 *db, const char *sql, int64_t *value) {
    sqlite3_stmt *statement;
    int rc = sqlite3_prepare_v2(db, sql, -1, &statement, NULL);
    if (rc != SQLITE_OK) return rc;
    *value = 0;
    rc = sqlite3_step(statement);
    if (rc == SQLITE_ROW) *value = sqlite3_column_int64(statement, 0), rc = SQLITE_OK;
    else if (rc == SQLITE_DONE) rc = SQLITE_OK;
    sqlite3_finalize(statement);
    return rc;
}

/* settings.value of `name` into `out` (empty when missing); the SQLite result code. */
static int setting_get(sqlite3 *db, const char *name, char *out, size_t out_size) {
    sqlite3_stmt *statement;
    out[0] = '\0';
    int rc = sqlite3_prepare_v2(db, "SELECT value FROM settings WHERE name = ?1", -1, &statement, NULL);
    if (rc != SQLITE_OK) return rc;
    sqlite3_bind_text(statement, 1, name, -1, SQLITE_STATIC);
    rc = sqlite3_step(statement);
    if (rc == SQLITE_ROW) {
        const unsigned char *text = sqlite3_column_text(statement, 0);
        snprintf(out, out_size, "%s", text ? (const char *)text : "");
        rc = SQLITE_OK;
    } else if (rc == SQLITE_DONE) rc = SQLITE_OK;
    sqlite3_finalize(statement);
    return rc;
}

static int setting_put(sqlite3 *db, const char *name, const char *value) {
    sqlite3_stmt *statement;
    int rc = sqlite3_prepare_v2(db, "INSERT OR REPLACE INTO settings(name, value) VALUES (?1, ?2)", -1, &statement,
                                NULL);
    if (rc != SQLITE_OK) return rc;
    sqlite3_bind_text(statement, 1, name, -1, SQLITE_STATIC);
    sqlite3_bind_text(statement, 2, value, -1, SQLITE_STATIC);
    rc = sqlite3_step(statement);
    sqlite3_finalize(statement);
    return rc == SQLITE_DONE ? SQLITE_OK : rc;
}

/* Whether a result code says the file is not a sound database (as opposed to a lock, a full
 * disk or an I/O error, which say nothing about the file). */
static bool damaged_code(int rc) {
    int primary = rc & 0xff;
    return primary == SQLITE_CORRUPT || primary == SQLITE_NOTADB;
}

/* ---- opening ------------------------------------------------------------------------------ */

typedef enum open_outcome {
    OPEN_OK,
    OPEN_DAMAGED,                     /* set it aside and start a new world */
    OPEN_REFUSED,                     /* opening.error says why; touch nothing */
} open_outcome;

typedef struct opening {
    terrain_store *store;
    terrain_store_report *report;
    terrain_edit_log *staging;        /* chunks read, moved to the store's log once all are good */
    core_error *error;                /* with OPEN_REFUSED: why (may be NULL) */
    char problem[400];                /* with OPEN_DAMAGED: what is wrong with the file */
} opening;

static open_outcome refuse(opening *o, int rc, const char *what) {
    terrain_store_report *r = o->report;
    if ((rc & 0xff) == SQLITE_BUSY || (rc & 0xff) == SQLITE_LOCKED) {
        r->in_use = true;
        core_error_set(o->error, CORE_ERROR_IO, "%s: in use by another process (close the other program first)",
                       o->store->path);
    } else
        core_error_set(o->error, CORE_ERROR_IO, "%s: %s (%s)", o->store->path, what,
                       o->store->db ? sqlite3_errmsg(o->store->db) : sqlite3_errstr(rc));
    return OPEN_REFUSED;
}

static open_outcome damaged(opening *o, const char *fmt, ...) CORE_PRINTF(2, 3);
static open_outcome damaged(opening *o, const char *fmt, ...) {
    va_list args;
    va_start(args, fmt);
    vsnprintf(o->problem, sizeof o->problem, fmt, args);
    va_end(args);
    return OPEN_DAMAGED;
}

/* A result code met while reading the file: damaged, or refused for any other reason. */
static open_outcome failed(opening *o, int rc, const char *what) {
    if (damaged_code(rc)) return damaged(o, "%s (%s)", what, sqlite3_errmsg(o->store->db));
    return refuse(o, rc, what);
}

static int create_schema(terrain_store *s, uint64_t seed, uint64_t key) {
    char sql[256], text[32];
    int rc = exec(s->db, "CREATE TABLE settings(name TEXT PRIMARY KEY, value TEXT NOT NULL);"
                         "CREATE TABLE chunks(x INTEGER NOT NULL, z INTEGER NOT NULL, edits BLOB NOT NULL,"
                         " PRIMARY KEY (x, z)) WITHOUT ROWID;"
                         "CREATE TABLE data(name TEXT PRIMARY KEY, value BLOB NOT NULL) WITHOUT ROWID;");
    snprintf(sql, sizeof sql, "PRAGMA application_id = %d; PRAGMA user_version = %d;", STORE_APPLICATION_ID,
             STORE_FORMAT);
    if (rc == SQLITE_OK) rc = exec(s->db, sql);
    snprintf(text, sizeof text, "%" PRIu64, seed);
    if (rc == SQLITE_OK) rc = setting_put(s->db, "seed", text);
    snprintf(text, sizeof text, "%016" PRIx64, key);
    if (rc == SQLITE_OK) rc = setting_put(s->db, "world_key", text);
    snprintf(text, sizeof text, "%d", STORE_FORMAT);
    if (rc == SQLITE_OK) rc = setting_put(s->db, "format", text);
    return rc;
}

/* The file is ours and of a format we read: its tables are there. */
static open_outcome check_identity(opening *o, int64_t application_id, int64_t format) {
    int64_t tables = 0;
    if (application_id != STORE_APPLICATION_ID)
        return damaged(o, "not a world database (application id %" PRId64 ")", application_id);
    if (format > STORE_FORMAT) {
        core_error_set(o->error, CORE_ERROR_VERSION,
                       "%s: made by a newer build (format %" PRId64 "; this one reads %d); left as it is",
                       o->store->path, format, STORE_FORMAT);
        return OPEN_REFUSED;
    }
    int rc = query_int(o->store->db, "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name IN"
                                     " ('settings', 'chunks', 'data')", &tables);
    if (rc != SQLITE_OK) return failed(o, rc, "cannot read its tables");
    if (tables != 3 || format < 1) return damaged(o, "a world database without its tables");
    return OPEN_OK;
}

/* SQLite's own structural check: every page, every b-tree, no index (there are none). */
static open_outcome check_structure(opening *o) {
    sqlite3_stmt *statement;
    int rc = sqlite3_prepare_v2(o->store->db, "PRAGMA quick_check(1)", -1, &statement, NULL);
    if (rc != SQLITE_OK) return failed(o, rc, "cannot be checked");
    rc = sqlite3_step(statement);
    open_outcome outcome = OPEN_OK;
    if (rc == SQLITE_ROW) {
        const char *verdict = (const char *)sqlite3_column_text(statement, 0);
        if (!verdict || strcmp(verdict, "ok") != 0)
            outcome = damaged(o, "fails SQLite's check: %s", verdict ? verdict : "?");
        for (char *c = o->problem; *c; c++)
            if (*c == '\n') *c = ' ';                /* the verdict's lines on one line */
    } else outcome = failed(o, rc, "cannot be checked");
    sqlite3_finalize(statement);
    return outcome;
}

static open_outcome check_world(opening *o) {
    char seed_text[32], key_text[32];
    int rc = setting_get(o->store->db, "seed", seed_text, sizeof seed_text);
    if (rc == SQLITE_OK) rc = setting_get(o->store->db, "world_key", key_text, sizeof key_text);
    if (rc != SQLITE_OK) return failed(o, rc, "cannot read its settings");
    char *end;
    uint64_t key = strtoull(key_text, &end, 16);
    if (!key_text[0] || *end) return damaged(o, "its world_key setting is '%s', not a key", key_text);
    uint64_t seed = strtoull(seed_text, &end, 10);
    bool seed_known = seed_text[0] && !*end;
    if (key == terrain__edit_log_key(o->store->edits)) return OPEN_OK;
    terrain_store_report *r = o->report;
    r->other_world = true;
    r->recorded_seed = seed_known ? seed : 0;
    if (seed_known)
        core_error_set(o->error, CORE_ERROR_MISMATCH, "%s: holds the world of seed %" PRIu64 " (or of another "
                       "generator); left as it is", o->store->path, seed);
    else core_error_set(o->error, CORE_ERROR_MISMATCH, "%s: holds another world; left as it is", o->store->path);
    return OPEN_REFUSED;
}

/* Every chunk row into the staging log; a row that fails its checks damns the file. */
static open_outcome read_chunks(opening *o) {
    sqlite3_stmt *statement;
    int rc = sqlite3_prepare_v2(o->store->db, "SELECT x, z, edits FROM chunks", -1, &statement, NULL);
    if (rc != SQLITE_OK) return failed(o, rc, "cannot read its chunks");
    open_outcome outcome = OPEN_OK;
    while (outcome == OPEN_OK && (rc = sqlite3_step(statement)) == SQLITE_ROW) {
        terrain_chunk_coord coord = { sqlite3_column_int64(statement, 0), sqlite3_column_int64(statement, 1) };
        const void *bytes = sqlite3_column_blob(statement, 2);
        size_t size = (size_t)sqlite3_column_bytes(statement, 2);
        core_error reason = { 0 };
        if (!terrain__edit_log_parse_chunk(o->staging, bytes, size, coord, &reason))
            outcome = damaged(o, "chunk (%lld, %lld): %s", (long long)coord.x, (long long)coord.z, reason.message);
        else o->report->chunks_loaded++;
    }
    if (outcome == OPEN_OK && rc != SQLITE_DONE) outcome = failed(o, rc, "cannot read its chunks");
    sqlite3_finalize(statement);
    return outcome;
}

static void values_clear(terrain_store *s) {
    for (size_t n = 0; n < s->value_count; n++) core_free(s->values[n].bytes, VALUE_ALLOC(s->values[n].size));
    s->value_count = 0;
}

static void value_set(terrain_store *s, const char *name, const void *bytes, size_t size, bool saved);

static open_outcome read_values(opening *o) {
    sqlite3_stmt *statement;
    int rc = sqlite3_prepare_v2(o->store->db, "SELECT name, value FROM data", -1, &statement, NULL);
    if (rc != SQLITE_OK) return failed(o, rc, "cannot read its values");
    open_outcome outcome = OPEN_OK;
    while (outcome == OPEN_OK && (rc = sqlite3_step(statement)) == SQLITE_ROW) {
        const char *name = (const char *)sqlite3_column_text(statement, 0);
        const void *bytes = sqlite3_column_blob(statement, 1);
        size_t size = (size_t)sqlite3_column_bytes(statement, 1);
        if (!name || strlen(name) > STORE_NAME_MAX || size > STORE_VALUE_MAX)
            outcome = damaged(o, "a value named '%.40s' of %zu bytes", name ? name : "", size);
        else value_set(o->store, name, size ? bytes : "", size, true);
    }
    if (outcome == OPEN_OK && rc != SQLITE_DONE) outcome = failed(o, rc, "cannot read its values");
    sqlite3_finalize(statement);
    return outcome;
}

/* What the file is, read before anything is written to it (a foreign file set aside must keep
 * its bytes): *fresh for an empty (new) file, OPEN_OK for one of ours. */
static open_outcome identify(opening *o, bool *fresh) {
    int64_t application_id, format, objects;
    int rc = query_int(o->store->db, "PRAGMA application_id", &application_id);
    if (rc == SQLITE_OK) rc = query_int(o->store->db, "PRAGMA user_version", &format);
    if (rc == SQLITE_OK) rc = query_int(o->store->db, "SELECT count(*) FROM sqlite_master", &objects);
    if (rc != SQLITE_OK) return failed(o, rc, "cannot be read");
    *fresh = application_id == 0 && format == 0 && objects == 0;
    return *fresh ? OPEN_OK : check_identity(o, application_id, format);
}

/* Inside the opening transaction: a new world gets its tables, an old one is checked and read. */
static open_outcome open_contents(opening *o, bool fresh, uint64_t seed) {
    terrain_store *s = o->store;
    if (fresh) {
        int rc = create_schema(s, seed, terrain__edit_log_key(s->edits));
        return rc == SQLITE_OK ? OPEN_OK : failed(o, rc, "cannot create the world's tables");
    }
    open_outcome outcome = check_structure(o);
    if (outcome == OPEN_OK) outcome = check_world(o);
    if (outcome == OPEN_OK) outcome = read_chunks(o);
    if (outcome == OPEN_OK) outcome = read_values(o);
    return outcome;
}

static void close_db(terrain_store *s) {
    sqlite3_finalize(s->put_chunk);
    sqlite3_finalize(s->put_value);
    s->put_chunk = s->put_value = NULL;
    sqlite3_close(s->db);
    s->db = NULL;
}

/* Opens (creating) the file with the exclusive lock, checks it and reads it. */
static open_outcome open_db(opening *o, uint64_t seed) {
    terrain_store *s = o->store;
    int rc = sqlite3_open_v2(s->path, &s->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, NULL);
    if (rc != SQLITE_OK) return refuse(o, rc, "cannot open");
    sqlite3_busy_timeout(s->db, 0);
    sqlite3_extended_result_codes(s->db, 1);
    /* Exclusive before WAL: then SQLite never makes a -shm file (the WAL index stays in memory). */
    rc = exec(s->db, "PRAGMA locking_mode = EXCLUSIVE");
    if (rc != SQLITE_OK) return failed(o, rc, "cannot be locked");
    bool fresh;
    open_outcome outcome = identify(o, &fresh);
    if (outcome != OPEN_OK) return outcome;
    sqlite3_stmt *statement;
    rc = sqlite3_prepare_v2(s->db, "PRAGMA journal_mode = WAL", -1, &statement, NULL);
    if (rc == SQLITE_OK) {
        rc = sqlite3_step(statement);
        if (rc == SQLITE_ROW) {
            const char *mode = (const char *)sqlite3_column_text(statement, 0);
            rc = mode && strcmp(mode, "wal") == 0 ? SQLITE_OK : SQLITE_CANTOPEN;
        }
        sqlite3_finalize(statement);
    }
    if (rc != SQLITE_OK) return failed(o, rc, "cannot be opened for writing");
    if ((rc = exec(s->db, "PRAGMA synchronous = FULL")) != SQLITE_OK) return failed(o, rc, "cannot be opened");
    if ((rc = exec(s->db, "BEGIN EXCLUSIVE")) != SQLITE_OK) return failed(o, rc, "cannot be locked");
    outcome = open_contents(o, fresh, seed);
    rc = exec(s->db, outcome == OPEN_OK ? "COMMIT" : "ROLLBACK");
    if (outcome == OPEN_OK && rc != SQLITE_OK) outcome = failed(o, rc, "cannot be written");
    return outcome;
}

/* Renames the damaged file (and its WAL) to world.db.bad, .bad.2, …: kept for a person. */
static bool set_aside(opening *o) {
    terrain_store *s = o->store;
    char *target = NULL;
    for (int n = 1; n < 1000; n++) {
        terrain__text_free(target);
        target = n == 1 ? terrain__text_format("%s.bad", s->path) : terrain__text_format("%s.bad.%d", s->path, n);
        if (!path_exists(target)) break;
    }
    bool ok = rename(s->path, target) == 0;
    terrain_store_report *r = o->report;
    if (!ok) {
        core_error_set(o->error, CORE_ERROR_IO, "%s: %s; cannot set it aside as %s (%s)", s->path, o->problem,
                       target, strerror(errno));
    } else {
        const char *suffixes[] = { "-wal", "-journal" };
        for (int n = 0; n < 2; n++) {
            char *from = terrain__text_format("%s%s", s->path, suffixes[n]);
            char *to = terrain__text_format("%s%s", target, suffixes[n]);
            if (path_exists(from) && rename(from, to) != 0)
                core_warn("terrain", "store: cannot rename %s to %s: %s", from, to, strerror(errno));
            terrain__text_free(from);
            terrain__text_free(to);
        }
        r->set_aside = true;
        snprintf(r->notice, sizeof r->notice, "%s: %s; set aside as %s, the world opens as generated", s->path,
                 o->problem, target);
        core_log_error("terrain", "store: %s", r->notice);
    }
    terrain__text_free(target);
    return ok;
}

static bool prepare_statements(terrain_store *s, core_error *error) {
    int rc = sqlite3_prepare_v2(s->db, "INSERT OR REPLACE INTO chunks(x, z, edits) VALUES (?1, ?2, ?3)", -1,
                                &s->put_chunk, NULL);
    if (rc == SQLITE_OK)
        rc = sqlite3_prepare_v2(s->db, "INSERT OR REPLACE INTO data(name, value) VALUES (?1, ?2)", -1, &s->put_value,
                                NULL);
    if (rc != SQLITE_OK)
        core_error_set(error, CORE_ERROR_IO, "%s: cannot prepare its statements (%s)", s->path, sqlite3_errmsg(s->db));
    return rc == SQLITE_OK;
}

/* ---- importing the old layout ------------------------------------------------------------ */

static void rename_old_folder(terrain_store *s, const char *folder, terrain_store_report *r) {
    char *target = NULL;
    for (int n = 1; n < 1000; n++) {
        terrain__text_free(target);
        target = n == 1 ? terrain__text_format("%s.imported", folder)
                        : terrain__text_format("%s.imported.%d", folder, n);
        if (!path_exists(target)) break;
    }
    if (rename(folder, target) != 0)
        core_warn("terrain", "store: %s is imported but cannot be renamed to %s (%s); it is not read again",
                  folder, target, strerror(errno));
    else if (r->chunks_imported || r->files_rejected)
        snprintf(r->notice + strlen(r->notice), sizeof r->notice - strlen(r->notice),
                 "%simported %d chunk(s) from %s (%d unreadable, renamed .bad); the old files are kept in %s",
                 r->notice[0] ? "; " : "", r->chunks_imported, folder, r->files_rejected, target);
    (void)s;
    terrain__text_free(target);
}

static bool write_snapshot(terrain_store *s, store_snapshot *snap, core_error *error);

/* The old DIR/edits folder of .tel files into the database in one transaction, once; then the folder is renamed. */
static bool import_old_layout(terrain_store *s, terrain_store_report *r, core_error *error) {
    char *folder = terrain__text_format("%s/edits", s->dir);
    char marker[32];
    bool ok = true;
    if (!is_folder(folder)) goto done;
    if (setting_get(s->db, "imported_edits", marker, sizeof marker) != SQLITE_OK) {
        core_error_set(error, CORE_ERROR_IO, "%s: cannot read its settings (%s)", s->path, sqlite3_errmsg(s->db));
        ok = false;
        goto done;
    }
    if (!marker[0]) {
        terrain_edit_log *staging = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain__edit_log_key(s->edits) });
        terrain_edit_log_load_result loaded;
        terrain_edit_log_load(staging, s->dir, &loaded, NULL);   /* a folder that cannot be listed: nothing to import */
        /* Every chunk read is clean in the staging log: written as "all", marked by the import. */
        store_snapshot snap = { .chunks = terrain__edit_log_all_files(staging, STORE_COMPACT_ABOVE) };
        core_error reason = { 0 };
        snprintf(snap.imported_edits, sizeof snap.imported_edits, "%d", loaded.chunks_loaded);
        if (!write_snapshot(s, &snap, &reason)) {
            core_error_set(error, reason.code, "cannot import %s: %s", folder, reason.message);
            ok = false;
        } else {
            terrain__edit_log_take(s->edits, staging);
            r->chunks_imported = loaded.chunks_loaded;
            r->chunks_loaded += loaded.chunks_loaded;
            r->files_rejected = loaded.files_rejected;
        }
        terrain__edit_files_free(&snap.chunks);
        terrain_edit_log_destroy(staging);
    }
    if (ok) rename_old_folder(s, folder, r);
done:
    terrain__text_free(folder);
    return ok;
}

/* ---- create and destroy ------------------------------------------------------------------ */

static void store_free(terrain_store *s) {
    close_db(s);
    values_clear(s);
    core_free(s->values, s->value_capacity * sizeof *s->values);
    terrain__text_free(s->dir);
    terrain__text_free(s->path);
    pthread_cond_destroy(&s->done);
    pthread_cond_destroy(&s->wake);
    pthread_mutex_destroy(&s->lock);
    pthread_mutex_destroy(&s->order);
    pthread_mutex_destroy(&s->db_lock);
    core_free(s, sizeof *s);
}

static bool desc_valid(const terrain_store_desc *desc, core_error *error) {
    if (!desc || !desc->dir || !desc->dir[0] || !desc->edits)
        return core_error_set(error, CORE_ERROR_ARGUMENT, "store: create needs %s",
                              !desc ? "a desc" : !desc->dir || !desc->dir[0] ? "a folder (desc.dir)" : "a log (desc.edits)");
    if (!core_make_dirs(desc->dir))
        return core_error_set(error, CORE_ERROR_IO, "%s: cannot create the world folder (%s)", desc->dir, strerror(errno));
    return true;
}

/* Opens the database, setting a damaged one aside once; false with `error`. */
static bool store_open(terrain_store *s, uint64_t seed, terrain_store_report *r, core_error *error) {
    for (int attempt = 0; attempt < 2; attempt++) {
        opening o = { .store = s, .report = r, .error = error,
                      .staging = terrain_edit_log_create(&(terrain_edit_log_desc){ .world_key = terrain__edit_log_key(s->edits) }) };
        open_outcome outcome = open_db(&o, seed);
        if (outcome == OPEN_OK) terrain__edit_log_take(s->edits, o.staging);
        terrain_edit_log_destroy(o.staging);
        if (outcome == OPEN_OK) return true;
        close_db(s);
        values_clear(s);
        r->chunks_loaded = 0;
        if (outcome == OPEN_REFUSED) return false;
        if (attempt == 1) {
            return core_error_set(error, CORE_ERROR_CORRUPT, "%s: a new database is damaged as soon as it is made: %s",
                                  s->path, o.problem);
        }
        if (!set_aside(&o)) return false;
    }
    return false;
}

terrain_store *terrain_store_create(const terrain_store_desc *desc, terrain_store_report *report, core_error *error) {
    terrain_store_report ignored;
    terrain_store_report *r = report ? report : &ignored;
    memset(r, 0, sizeof *r);
    if (!desc_valid(desc, error)) return NULL;
    terrain_store *s = core_calloc(1, sizeof *s);
    s->dir = terrain__text_format("%s", desc->dir);
    s->path = terrain__text_format("%s/" STORE_FILE, desc->dir);
    s->edits = desc->edits;
    s->last_ok = true;
    pthread_mutex_init(&s->db_lock, NULL);
    pthread_mutex_init(&s->order, NULL);
    pthread_mutex_init(&s->lock, NULL);
    pthread_cond_init(&s->wake, NULL);
    pthread_cond_init(&s->done, NULL);
    bool ok = store_open(s, desc->seed, r, error) && prepare_statements(s, error) && import_old_layout(s, r, error);
    if (!ok) {
        store_free(s);
        return NULL;
    }
    return s;
}

static void stop_thread(terrain_store *s) {
    pthread_mutex_lock(&s->lock);
    while (s->busy) pthread_cond_wait(&s->done, &s->lock);
    s->stopping = true;
    pthread_cond_signal(&s->wake);
    bool started = s->thread_started;
    pthread_mutex_unlock(&s->lock);
    if (started) pthread_join(s->thread, NULL);
}

void terrain_store_destroy(terrain_store *store) {
    if (!store) return;
    stop_thread(store);
    store_free(store);
}

/* ---- named values ------------------------------------------------------------------------- */

static store_value *value_find(terrain_store *s, const char *name) {
    for (size_t n = 0; n < s->value_count; n++)
        if (strcmp(s->values[n].name, name) == 0) return &s->values[n];
    return NULL;
}

/* Lock held (or the store not shared yet). */
static void value_set(terrain_store *s, const char *name, const void *bytes, size_t size, bool saved) {
    store_value *v = value_find(s, name);
    if (v && v->size == size && memcmp(v->bytes, bytes, size) == 0) return;
    if (!v) {
        s->values = core_grow(s->values, &s->value_capacity, s->value_count + 1, sizeof *s->values);
        v = &s->values[s->value_count++];
        *v = (store_value){ 0 };
        snprintf(v->name, sizeof v->name, "%s", name);
    }
    if (v->bytes) core_free(v->bytes, VALUE_ALLOC(v->size));
    v->bytes = core_alloc(VALUE_ALLOC(size));
    if (size) memcpy(v->bytes, bytes, size);
    v->size = size;
    v->version++;
    if (saved) v->saved_version = v->version;
}

bool terrain_store_put(terrain_store *store, const char *name, const void *bytes, size_t size) {
    if (!store || !name || !name[0] || strlen(name) > STORE_NAME_MAX || (!bytes && size) || size > STORE_VALUE_MAX) {
        core_log_error("terrain", "store: put of %s refused (names of 1 to %d bytes, values up to %zu bytes)",
                   name ? name : "(no name)", STORE_NAME_MAX, STORE_VALUE_MAX);
        return false;
    }
    pthread_mutex_lock(&store->lock);
    value_set(store, name, size ? bytes : "", size, false);
    pthread_mutex_unlock(&store->lock);
    return true;
}

int64_t terrain_store_get(terrain_store *store, const char *name, void *bytes, size_t capacity) {
    if (!store || !name) return -1;
    pthread_mutex_lock(&store->lock);
    store_value *v = value_find(store, name);
    int64_t size = v ? (int64_t)v->size : -1;
    if (v && bytes) memcpy(bytes, v->bytes, CORE_MIN(v->size, capacity));
    pthread_mutex_unlock(&store->lock);
    return size;
}

/* ---- saving -------------------------------------------------------------------------------- */

/* Lock held. */
static void snapshot_values(terrain_store *s, store_snapshot *snap) {
    for (size_t n = 0; n < s->value_count; n++) {
        store_value *v = &s->values[n];
        if (v->version == v->saved_version) continue;
        snap->values = core_grow(snap->values, &snap->value_capacity, snap->value_count + 1, sizeof *snap->values);
        store_value_copy *c = &snap->values[snap->value_count++];
        snprintf(c->name, sizeof c->name, "%s", v->name);
        c->size = v->size;
        c->version = v->version;
        c->bytes = core_alloc(VALUE_ALLOC(v->size));
        memcpy(c->bytes, v->bytes, v->size);
    }
}

static store_snapshot *snapshot_take(terrain_store *s) {
    store_snapshot *snap = core_calloc(1, sizeof *snap);
    snap->chunks = terrain__edit_log_dirty_files(s->edits, STORE_COMPACT_ABOVE);
    pthread_mutex_lock(&s->lock);
    snapshot_values(s, snap);
    pthread_mutex_unlock(&s->lock);
    return snap;
}

static bool snapshot_empty(const store_snapshot *snap) {
    return snap->chunks.count == 0 && snap->value_count == 0;
}

static void snapshot_free(store_snapshot *snap) {
    terrain__edit_files_free(&snap->chunks);
    for (size_t n = 0; n < snap->value_count; n++) core_free(snap->values[n].bytes, VALUE_ALLOC(snap->values[n].size));
    core_free(snap->values, snap->value_capacity * sizeof *snap->values);
    core_free(snap, sizeof *snap);
}

static int bind_and_step(sqlite3_stmt *statement) {
    int rc = sqlite3_step(statement);
    sqlite3_reset(statement);
    sqlite3_clear_bindings(statement);
    return rc == SQLITE_DONE ? SQLITE_OK : rc;
}

/* The rows of one snapshot; db_lock held, inside a transaction. */
static int write_rows(terrain_store *s, const store_snapshot *snap) {
    int rc = SQLITE_OK;
    for (size_t n = 0; n < snap->chunks.count && rc == SQLITE_OK; n++) {
        const terrain__edit_file *f = &snap->chunks.items[n];
        sqlite3_bind_int64(s->put_chunk, 1, f->coord.x);
        sqlite3_bind_int64(s->put_chunk, 2, f->coord.z);
        rc = sqlite3_bind_blob64(s->put_chunk, 3, f->bytes, f->size, SQLITE_STATIC);
        if (rc == SQLITE_OK) rc = bind_and_step(s->put_chunk);
        else sqlite3_reset(s->put_chunk);
    }
    for (size_t n = 0; n < snap->value_count && rc == SQLITE_OK; n++) {
        const store_value_copy *v = &snap->values[n];
        sqlite3_bind_text(s->put_value, 1, v->name, -1, SQLITE_STATIC);
        sqlite3_bind_blob64(s->put_value, 2, v->bytes, v->size, SQLITE_STATIC);
        rc = bind_and_step(s->put_value);
    }
    if (rc == SQLITE_OK && snap->imported_edits[0]) rc = setting_put(s->db, "imported_edits", snap->imported_edits);
    return rc;
}

/* One transaction; db_lock held. On success every file is marked written. */
static bool write_snapshot(terrain_store *s, store_snapshot *snap, core_error *error) {
    int rc = exec(s->db, "BEGIN IMMEDIATE");
    if (rc == SQLITE_OK) rc = write_rows(s, snap);
    if (rc == SQLITE_OK) rc = exec(s->db, "COMMIT");
    if (rc != SQLITE_OK) {
        const char *message = sqlite3_errmsg(s->db);
        core_error_set(error, CORE_ERROR_IO, "%s: cannot save (%s)", s->path, message ? message : sqlite3_errstr(rc));
        if (!sqlite3_get_autocommit(s->db)) exec(s->db, "ROLLBACK");
        return false;
    }
    for (size_t n = 0; n < snap->chunks.count; n++) snap->chunks.items[n].written = true;
    return true;
}

/* Marks what a committed snapshot held as saved (values changed meanwhile stay dirty). */
static void snapshot_mark_saved(terrain_store *s, const store_snapshot *snap) {
    terrain__edit_log_mark_saved(s->edits, &snap->chunks);
    pthread_mutex_lock(&s->lock);
    for (size_t n = 0; n < snap->value_count; n++) {
        store_value *v = value_find(s, snap->values[n].name);
        if (v && snap->values[n].version > v->saved_version) v->saved_version = snap->values[n].version;
    }
    pthread_mutex_unlock(&s->lock);
}

/* Writes and marks a snapshot, in a trace zone; any thread. */
static bool commit_snapshot(terrain_store *s, store_snapshot *snap, core_error *error) {
    TRACE_ZONE("terrain.store.save");
    pthread_mutex_lock(&s->db_lock);
    bool ok = write_snapshot(s, snap, error);
    pthread_mutex_unlock(&s->db_lock);
    if (ok) snapshot_mark_saved(s, snap);
    return ok;
}

/* What terrain_store_wait reports next. */
static void record_outcome(terrain_store *s, bool ok, const core_error *error) {
    pthread_mutex_lock(&s->lock);
    s->last_ok = ok;
    s->last_error = ok || !error ? (core_error){ 0 } : *error;
    s->busy = false;
    pthread_cond_broadcast(&s->done);
    pthread_mutex_unlock(&s->lock);
}

static void *save_thread(void *arg) {
    terrain_store *s = arg;
    trace_thread_name("terrain.store");
    pthread_mutex_lock(&s->lock);
    for (;;) {
        while (!s->queued && !s->stopping) pthread_cond_wait(&s->wake, &s->lock);
        if (!s->queued) break;
        store_snapshot *snap = s->queued;
        s->queued = NULL;
        pthread_mutex_unlock(&s->lock);
        core_error error = { 0 };
        bool ok = commit_snapshot(s, snap, &error);
        /* Nobody waits on this thread: the failure is logged here, and kept for terrain_store_wait. */
        if (!ok) core_log_error("terrain", "store: %s; the changes stay for the next save", error.message);
        snapshot_free(snap);
        record_outcome(s, ok, &error);
        pthread_mutex_lock(&s->lock);
    }
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

bool terrain_store_wait(terrain_store *store, core_error *error) {
    if (!store) return core_error_set(error, CORE_ERROR_ARGUMENT, "store: wait with no store");
    pthread_mutex_lock(&store->lock);
    while (store->busy) pthread_cond_wait(&store->done, &store->lock);
    bool ok = store->last_ok;
    if (!ok && error) *error = store->last_error;
    pthread_mutex_unlock(&store->lock);
    return ok;
}

bool terrain_store_save(terrain_store *store, core_error *error) {
    if (!store) return core_error_set(error, CORE_ERROR_ARGUMENT, "store: save with no store");
    /* An older snapshot committed after a newer one would put old bytes in the file while the
     * chunks read as saved: snapshots are taken and committed in one order. */
    pthread_mutex_lock(&store->order);
    terrain_store_wait(store, NULL);
    store_snapshot *snap = snapshot_take(store);
    core_error failure = { 0 };
    bool ok = snapshot_empty(snap) || commit_snapshot(store, snap, &failure);
    pthread_mutex_unlock(&store->order);
    snapshot_free(snap);
    record_outcome(store, ok, &failure);
    if (!ok && error) *error = failure;
    return ok;
}

bool terrain_store_save_async(terrain_store *store) {
    if (!store) return false;
    pthread_mutex_lock(&store->order);
    pthread_mutex_lock(&store->lock);
    bool busy = store->busy;
    pthread_mutex_unlock(&store->lock);
    if (busy) {
        pthread_mutex_unlock(&store->order);
        return false;
    }
    TRACE_ZONE("terrain.store.snapshot");
    store_snapshot *snap = snapshot_take(store);
    if (snapshot_empty(snap)) {
        pthread_mutex_unlock(&store->order);
        snapshot_free(snap);
        return true;
    }
    pthread_mutex_lock(&store->lock);
    if (!store->thread_started) {
        if (pthread_create(&store->thread, NULL, save_thread, store) != 0)
            core_fatal("terrain", "store: cannot start its thread");
        store->thread_started = true;
    }
    store->queued = snap;
    store->busy = true;
    pthread_cond_signal(&store->wake);
    pthread_mutex_unlock(&store->lock);
    pthread_mutex_unlock(&store->order);
    return true;
}

/* ---- reading the seed without opening the world ------------------------------------------- */

int terrain_store_read_seed(const char *dir, uint64_t *seed, core_error *error) {
    if (!dir || !dir[0]) {
        core_error_set(error, CORE_ERROR_ARGUMENT, "store: no folder");
        return -1;
    }
    char *path = terrain__text_format("%s/" STORE_FILE, dir);
    int result = 0;
    sqlite3 *db = NULL;
    if (!path_exists(path)) goto done;
    result = -1;
    /* Read-write without create, exclusive like the store: a WAL database read this way makes
     * no -shm file, and a world another process holds answers SQLITE_BUSY at once. */
    int rc = sqlite3_open_v2(path, &db, SQLITE_OPEN_READWRITE, NULL);
    if (rc == SQLITE_OK) sqlite3_busy_timeout(db, 0), rc = exec(db, "PRAGMA locking_mode = EXCLUSIVE");
    char text[32] = "";
    if (rc == SQLITE_OK) rc = setting_get(db, "seed", text, sizeof text);
    char *end;
    unsigned long long value = strtoull(text, &end, 10);
    if ((rc & 0xff) == SQLITE_BUSY) core_error_set(error, CORE_ERROR_IO, "%s: in use by another process", path);
    else if (rc != SQLITE_OK)
        core_error_set(error, damaged_code(rc) ? CORE_ERROR_CORRUPT : CORE_ERROR_IO, "%s: cannot be read (%s)", path,
                          db ? sqlite3_errmsg(db) : sqlite3_errstr(rc));
    else if (!text[0] || *end) core_error_set(error, CORE_ERROR_FORMAT, "%s: records no seed", path);
    else *seed = value, result = 1;
done:
    sqlite3_close(db);
    terrain__text_free(path);
    return result;
}
