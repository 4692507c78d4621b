// Browser test of `rastercheck view`: headless Chromium (Debian's chromium, driven by puppeteer-core)
// loads the page for the crane in the plant, types a luff angle that swings the boom into the pipe
// rack, and checks that the page reports the collision (status, contacts, raster image) and draws it
// (the view is not blank and has red in it); Ctrl+Z must bring back the free state, the Redo and
// Undo buttons must go back and forth, the request's path must play back to its goal, and Plan must
// fill the timeline with a planned path that plays to the goal.
//
// Usage: node tests/browser/view_page.mjs RASTERCHECK_CLI SOURCE_DIR [SCREENSHOT.png]
// Exit status: 0 passed, 1 failed, 77 skipped (only when Chromium is not installed or cannot start).
import {spawn} from 'node:child_process';
import {existsSync} from 'node:fs';
import path from 'node:path';

const [cli, sourceDir, screenshotPath] = process.argv.slice(2);
const SKIP = 77;
const TIMEOUT_MS = 60000;  // a sanitized build answers 10 to 50 times slower

// Known answers (the HTTP API test checks the same states): the crane on its lift site, slewed to
// face the pipe rack (+y), the boom raised and the hook drawn up: free. Luffing down to 0.3 rad
// lowers the boom through bent 06 of the rack and the pipes on it.
const FREE = [0, 0, 0, 1.570796326795, 0.834431313317, 5, 1];
const LUFF = 4;
const LUFF_INTO_RACK = 0.3;
const COLLIDING = FREE.map((value, i) => (i === LUFF ? LUFF_INTO_RACK : value));
// robots/sites/plant_lift.yaml's goal, where the playback of its straight line ends.
const GOAL = [0, 0, 0, 1.570796326795, 0.71942438464, 8.5, 20.933726302844];

function fail(message)
{
    console.error(`FAIL: ${message}`);
    process.exitCode = 1;
    throw new Error(message);
}

function expect(condition, message)
{
    if (!condition)
        fail(message);
    console.log(`ok: ${message}`);
}

function findChromium()
{
    const candidates =
        [process.env.RASTERCHECK_CHROMIUM, '/usr/bin/chromium', '/usr/bin/chromium-browser', '/usr/bin/google-chrome'];
    return candidates.find((candidate) => candidate && existsSync(candidate));
}

/** Starts the viewer on a free port and resolves to { server, url } once it prints its URL. */
function startServer()
{
    const server = spawn(
        cli,
        [
            'view',
            '--robot',
            path.join(sourceDir, 'robots/crane/crane.urdf'),
            '--srdf',
            path.join(sourceDir, 'robots/crane/crane.srdf'),
            '--scene',
            path.join(sourceDir, 'robots/sites/plant.yaml'),
            '--request',
            path.join(sourceDir, 'robots/sites/plant_lift.yaml'),
            '--port',
            '0',
        ],
        {stdio: ['ignore', 'pipe', 'pipe']});
    return new Promise((resolve, reject) => {
        let output = '';
        const timer =
            setTimeout(() => reject(new Error(`no URL from the server in ${TIMEOUT_MS} ms:\n${output}`)), TIMEOUT_MS);
        const read = (chunk) => {
            output += chunk;
            const match = /open (http:\/\/\S+)/.exec(output);
            if (match)
            {
                clearTimeout(timer);
                resolve({server, url: match[1]});
            }
        };
        server.stdout.on('data', read);
        server.stderr.on('data', read);
        server.on('exit', (code) => reject(new Error(`the server exited (${code}) before serving:\n${output}`)));
    });
}

/** Waits until the page shows the answer for configuration \a q and returns the status. */
async function answerFor(page, q)
{
    await page.waitForFunction((expected) => {
        const status = document.getElementById('status');
        return document.body.dataset.busy === 'false' && status.dataset.q === expected;
    }, {timeout: TIMEOUT_MS}, JSON.stringify(q));
    return page.$eval('#status', (status) => ({state: status.dataset.state, text: status.textContent}));
}

/** What the 3D view shows: the fraction of pixels unlike the background, distinct colours and red pixels. */
async function viewPixels(page)
{
    const view = await page.$('#view');
    const png = await view.screenshot({encoding: 'base64'});
    return page.evaluate(async (data) => {
        const bytes = Uint8Array.from(atob(data), (c) => c.charCodeAt(0));
        const bitmap = await createImageBitmap(new Blob([bytes], {type: 'image/png'}));
        const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
        const context = canvas.getContext('2d');
        context.drawImage(bitmap, 0, 0);
        const pixels = context.getImageData(0, 0, bitmap.width, bitmap.height).data;
        const background = [pixels[0], pixels[1], pixels[2]];
        const colours = new Set();
        let drawn = 0;
        let red = 0;
        for (let i = 0; i < pixels.length; i += 4)
        {
            const [r, g, b] = [pixels[i], pixels[i + 1], pixels[i + 2]];
            colours.add(((r >> 3) << 10) | ((g >> 3) << 5) | (b >> 3));
            if (Math.abs(r - background[0]) + Math.abs(g - background[1]) + Math.abs(b - background[2]) > 24)
                ++drawn;
            if (r > 170 && g < 90 && b < 90)
                ++red;
        }
        const total = pixels.length / 4;
        return {drawn: drawn / total, colours: colours.size, red, total};
    }, png);
}

async function main()
{
    if (!cli || !sourceDir)
    {
        console.error('usage: node tests/browser/view_page.mjs RASTERCHECK_CLI SOURCE_DIR [SCREENSHOT.png]');
        return 2;
    }
    let puppeteer;
    try
    {
        puppeteer = (await import('puppeteer-core')).default;
    }
    catch (error)
    {
        console.error(
            `FAIL: puppeteer-core is not installed (${error.message}); scripts/install-deps.sh installs ` +
            'it (npm ci in the repository root)');
        return 1;
    }
    const chromium = findChromium();
    if (!chromium)
    {
        console.log(
            'SKIP: Chromium is not installed (scripts/install-deps.sh installs Debian\'s chromium; ' +
            'RASTERCHECK_CHROMIUM names another browser)');
        return SKIP;
    }
    let browser;
    try
    {
        // --no-sandbox: CI runs as root, where Chromium's sandbox refuses to start. SwiftShader: WebGL
        // without a GPU.
        browser = await puppeteer.launch({
            executablePath: chromium,
            headless: true,
            timeout: TIMEOUT_MS,
            args: ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--disable-dev-shm-usage'],
        });
    }
    catch (error)
    {
        console.log(`SKIP: Chromium (${chromium}) cannot start: ${error.message}`);
        return SKIP;
    }
    const {server, url} = await startServer();
    try
    {
        const page = await browser.newPage();
        const pageErrors = [];
        page.on('pageerror', (error) => pageErrors.push(error.message));
        await page.setViewport({width: 1400, height: 850});
        await page.goto(`${url}#q=${FREE.join(',')}`, {timeout: TIMEOUT_MS});

        let status = await answerFor(page, FREE);
        expect(
            status.state === 'valid' && status.text === 'Collision-free',
            `the free state shows as free (status '${status.text}')`);
        const clearance =
            await page.$eval('#clearance', (span) => ({text: span.textContent, distance: span.dataset.distance}));
        expect(
            Number(clearance.distance) > 0 && clearance.text.startsWith('clearance '),
            `the free state shows its clearance ('${clearance.text}')`);
        const joints =
            await page.$$eval('#joints .joint label span:first-child', (labels) => labels.map((l) => l.textContent));
        expect(
            joints.join() === 'base_x (m),base_y (m),base_yaw (rad),slew (rad),luff (rad),telescope_1 (m),hoist (m)',
            `one slider per coordinate, with units (${joints.join(', ')})`);
        const free = await viewPixels(page);
        expect(free.red === 0, `no red in the free state's view (${free.red} red pixels)`);

        // Type the luff angle as a user does: select the field, type, Enter.
        const luffField = `#joint-${LUFF}-number`;
        await page.click(luffField, {clickCount: 3});
        await page.type(luffField, String(LUFF_INTO_RACK));
        await page.keyboard.press('Enter');
        status = await answerFor(page, COLLIDING);
        expect(status.state === 'colliding', `luff ${LUFF_INTO_RACK} shows a collision (status '${status.text}')`);
        const slider = await page.$eval(`#joint-${LUFF}-slider`, (input) => Number(input.value));
        expect(Math.abs(slider - LUFF_INTO_RACK) < 1e-9, `the luff slider follows the typed value (${slider})`);
        const contacts = await page.$$eval(
            '#contacts li', (items) => items.map((item) => `${item.dataset.component}|${item.dataset.object}`));
        expect(
            contacts.length === 12 && status.text === 'Collision: 12 contacts',
            `the page lists the 12 contacts of this state (${contacts.length})`);
        expect(
            contacts.includes('boom_section_1|pipe_rack_bent_06/0') && contacts.includes('boom_section_3|pipe_5'),
            'the contacts name the boom sections against bent 06 of the pipe rack and pipe 5');
        expect(contacts.every((pair) => pair.startsWith('boom_section_')), 'only boom sections collide');
        await page.waitForFunction(() => {
            const image = document.getElementById('raster');
            return !image.hidden && image.complete && image.naturalWidth > 0;
        }, {timeout: TIMEOUT_MS});
        expect(true, 'the raster image of the first colliding pair is shown');
        const colliding = await viewPixels(page);
        expect(
            colliding.drawn > 0.05 && colliding.colours > 20,
            `the view is not blank (${(100 * colliding.drawn).toFixed(1)} % drawn, ${colliding.colours} colours)`);
        expect(colliding.red > 200, `the boom and the hit triangles are red (${colliding.red} red pixels)`);
        if (screenshotPath)
        {
            await page.screenshot({path: screenshotPath});
            console.log(`wrote ${screenshotPath}`);
        }

        await page.click('#view');  // focus off the number field: Ctrl+Z must undo the edit, not the text
        await page.keyboard.down('Control');
        await page.keyboard.press('z');
        await page.keyboard.up('Control');
        status = await answerFor(page, FREE);
        expect(status.state === 'valid', `Ctrl+Z returns to the free state (status '${status.text}')`);
        const undone = await viewPixels(page);
        expect(undone.red === 0, `no red after the undo (${undone.red} red pixels)`);
        await page.click('#redo');
        status = await answerFor(page, COLLIDING);
        expect(status.state === 'colliding', 'the Redo button brings the collision back');
        await page.click('#undo');
        status = await answerFor(page, FREE);
        expect(status.state === 'valid', 'the Undo button returns to the free state');

        // Playback of the request's straight line from start to goal: the path's two states are free,
        // it ends at the goal, and undo returns to where it started.
        const pathInfo = await page.$eval('#path-info', (info) => info.textContent);
        expect(pathInfo === '2 path states, 0 colliding', `the timeline shows the path's verdicts (${pathInfo})`);
        await page.click('#play');
        await page.waitForFunction(() => document.getElementById('play').textContent === 'Play', {timeout: TIMEOUT_MS});
        status = await answerFor(page, GOAL);
        expect(status.state === 'valid', 'playback ends at the goal, free');
        await page.keyboard.down('Control');
        await page.keyboard.press('z');
        await page.keyboard.up('Control');
        status = await answerFor(page, FREE);
        expect(status.state === 'valid', 'Ctrl+Z after the playback returns to the state it started from');

        // Plan from here to the request's goal (POST api/plan): the planned path fills the timeline,
        // all its states free, and plays to the goal.
        await page.$eval('#time-limit', (input) => { input.value = '20'; });
        await page.click('#plan');
        await page.waitForFunction(() => ['solved', 'failed'].includes(document.getElementById('plan-info').dataset.state),
                                   {timeout: TIMEOUT_MS});
        const planInfo = await page.$eval('#plan-info', (info) => `${info.dataset.state}: ${info.textContent}`);
        expect(planInfo.startsWith('solved: BatchRRTConnect: '), `Plan finds a path (${planInfo})`);
        const planned = await page.$eval('#path-info', (info) => info.textContent);
        const timelineMax = await page.$eval('#timeline', (timeline) => Number(timeline.max));
        const states = Number(planned.split(' ')[0]);
        expect(/^\d+ path states, 0 colliding$/.test(planned) && states >= 2 && timelineMax === states - 1,
               `the timeline holds the planned path (${planned}, timeline max ${timelineMax})`);
        await page.waitForFunction(() => document.getElementById('play').textContent === 'Play', {timeout: TIMEOUT_MS});
        status = await answerFor(page, GOAL);
        expect(status.state === 'valid', 'the planned path plays to the goal, free');
        await page.click('#set-goal');
        const goalInfo = await page.$eval('#plan-info', (info) => info.textContent);
        expect(goalInfo === 'Goal set to the current configuration.', `Set goal says so (${goalInfo})`);
        expect(pageErrors.length === 0, `no script errors on the page (${pageErrors.join('; ')})`);
        return 0;
    }
    finally
    {
        await browser.close();
        server.kill('SIGTERM');
    }
}

main()
    .then((status) => {
        process.exitCode = process.exitCode || status;
    })
    .catch((error) => {
        if (!process.exitCode)
            console.error(`FAIL: ${error.stack || error.message}`);
        process.exitCode = 1;
    });
